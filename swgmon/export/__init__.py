"""The condition monitor's per-window stage as C99 for a microcontroller (swgsim-export).

One concern per module:

* :mod:`.reference` - the stage's arithmetic in Python (float32, op for op as the C);
* :mod:`.data` - simulated gear lives through it, each gear's normal behaviour;
* :mod:`.forest` - the exported classifier (random forest, emlearn) and its refusals;
* :mod:`.ctemplates`, :mod:`.cgen` - the C sources and tables;
* :mod:`.host` - the C compiled for the host and run on windows;
* :mod:`.firmware`, :mod:`.target` - the Cortex-M4F image, its size and cycle count;
* :mod:`.pipeline` - the export from end to end.

Method, interface and figures: ``docs/EXPORT.md``.
"""


def import_emlearn():
    """emlearn, imported with numpy's floating-point error state kept as it was.

    emlearn 0.23.2 calls ``numpy.seterr(all='raise')`` when imported (its ``bayes``
    module, loaded by ``emlearn.convert``): every later underflow anywhere in the process
    would raise. Found when the test suite ran test_export before the calibration tests.
    """
    import numpy as np

    with np.errstate():  # restores the state on the way out
        import emlearn
        import emlearn.trees  # noqa: F401
    return emlearn

