"""The condition monitor: a gear's own healthy baseline, a sequential alarm rule with a
design false-alarm rate, and the naming of the fault and its severity after an alarm
(ISO 13374's state detection and health assessment). Layers: :mod:`.features` (one
window's health features), :mod:`.rule` (conformal p-values and their CUSUM),
:mod:`.model` (baseline and diagnosis model), :mod:`.monitor` (one gear's stream),
:mod:`.evaluate` (leave-one-gear-out lives)."""
