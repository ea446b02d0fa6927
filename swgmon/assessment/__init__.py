"""Health assessment (ISO 13374): the diagnosis model, which names the fault and its
severity (:mod:`.model`, compiled :mod:`.trees`, on disk :mod:`.model_io`), the checks of
the bridges and the temperature sensor (:mod:`.sensor_check`), the unexplained change
(:mod:`.unexplained`) and one gear's monitor that holds them (:mod:`.gear_monitor`)."""
