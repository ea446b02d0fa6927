"""Classifiers behind the scikit-learn interface: the paper's Table VI models and the
model registry (:mod:`learn.learners.models`), torch MLP and 1D-CNN
(:mod:`learn.learners.nets`), MiniRocket (:mod:`learn.learners.rocket`) and CORAL
(:mod:`learn.learners.adapt`). Imports only :mod:`learn.inputs`, never a study or a
report."""
