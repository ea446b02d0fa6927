"""What the learners see, computed from a data set: the paper's features (Table III,
:mod:`learn.inputs.features`, with the one registry of feature selections) and the
signal inputs of the deep learners (:mod:`learn.inputs.signals`), every one normalised by
the reference windows of its gear. The lowest layer of :mod:`learn`: imports no other
part of it."""
