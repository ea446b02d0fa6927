"""State detection (ISO 13374): a gear's own normal behaviour under its operating
variables (:mod:`.normal`, its laws :mod:`.laws`) and the alarm rule, conformal p-values
and their CUSUM (:mod:`.rule`)."""
