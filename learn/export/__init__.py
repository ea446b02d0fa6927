"""The condition monitor's per-window stage as C99 for a microcontroller (swgsim-export).

One concern per module:

* :mod:`.reference` - the stage's arithmetic in Python (float32, op for op as the C);
* :mod:`.data` - simulated gear lives through it, each gear's baseline;
* :mod:`.forest` - the exported classifier (random forest, emlearn) and its refusals;
* :mod:`.ctemplates`, :mod:`.cgen` - the C sources and tables;
* :mod:`.host` - the C compiled for the host and run on windows;
* :mod:`.firmware`, :mod:`.target` - the Cortex-M4F image, its size and cycle count;
* :mod:`.pipeline` - the export from end to end.

Method, interface and figures: ``docs/EXPORT.md``.
"""
