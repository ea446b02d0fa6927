"""Advisory generation (ISO 13374): a stream of windows through the monitor, with its
maintenance log, recommissioning and advisories (:mod:`.stream`), and its figures
(:mod:`.figures`)."""
