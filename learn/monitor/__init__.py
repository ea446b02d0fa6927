"""The condition monitor: a gear's own normal behaviour, a sequential alarm rule with a
design false-alarm rate, and the naming of the fault and its severity after an alarm
(ISO 13374's state detection and health assessment). Layers: :mod:`.features` (one
window's health features), :mod:`.rule` (conformal p-values and their CUSUM),
:mod:`.model` (normal behaviour and diagnosis model), :mod:`.gear_monitor` (one gear's stream),
:mod:`.evaluate` (leave-one-gear-out lives)."""
