"""Advisory generation (ISO 13374): a stream of windows through the monitor, with its
maintenance log and recommissioning (:mod:`.stream`), what it tells of it: events,
advisories, outputs (:mod:`.report`), and its figures (:mod:`.figures`)."""
