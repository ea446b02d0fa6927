"""Prognostic assessment (ISO 13374): the remaining useful life after an alarm - its
inputs and outputs (:mod:`.inputs`), the growth law's prediction (:mod:`.growth`), the
baselines (:mod:`.baselines`), conformal calibration (:mod:`.calibration`), the scores
(:mod:`.scores`) and the prognosis along a stream (:mod:`.stream`)."""
