"""The exported C compiled for the host (system C compiler) and run on windows (ctypes).

Flags: ``-std=c99 -O2 -ffp-contract=off`` (IEEE float32 arithmetic in the source's order,
as the reference, no fused multiply-add), ``-Wall -Wextra``.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np

CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-Wall", "-Wextra")


def find_cc() -> str | None:
    """The system C compiler (``cc``, ``gcc`` or ``clang``), or None."""
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return path
    return None


def build(src: Path, out: Path) -> Path:
    """Compile ``src/swg_monitor.c`` into the shared library ``out`` (a path).

    Raises
    ------
    RuntimeError
        No C compiler, or one line naming it, its exit status and its first error line.
    """
    cc = find_cc()
    if cc is None:
        raise RuntimeError("no C compiler (cc, gcc or clang) on PATH")
    cmd = [cc, *CFLAGS, "-shared", "-I", str(src), str(src / "swg_monitor.c"), "-o",
           str(out), "-lm"]
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise RuntimeError(f"{Path(cc).name} failed ({getattr(e, 'strerror', None) or e})"
                           ) from None
    if res.returncode:
        lines = [" ".join(s.split()) for s in res.stderr.splitlines() if s.strip()]
        first = next((s for s in lines if "error" in s), lines[0] if lines else "")[:200]
        raise RuntimeError(f"{Path(cc).name} failed (exit {res.returncode}) compiling "
                           f"swg_monitor.c for the host: {first}")
    return out


class HostStage:
    """The compiled stage; :meth:`run` gives classes, P(healthy) and features.

    Parameters
    ----------
    lib : Path
        Shared library of :func:`build`.
    n_features : int
    """

    def __init__(self, lib: Path, n_features: int) -> None:
        self.lib = ctypes.CDLL(str(lib))
        f = self.lib.swg_run_window
        fp = ctypes.POINTER(ctypes.c_float)
        f.argtypes = [fp, fp, ctypes.c_int32, ctypes.c_int32, ctypes.c_float, fp, fp]
        f.restype = ctypes.c_int32
        self.n_features = n_features

    def run(self, signals: np.ndarray, phi: np.ndarray, op: np.ndarray,
            efficiency: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Windows through ``swg_run_window``.

        Parameters
        ----------
        signals : ndarray, shape (n, 5, n_t)
            Bridge outputs [mV/V].
        phi : ndarray, shape (n, n_t)
            Input angle since each window's first sample [rad].
        op : ndarray of int, shape (n,)
        efficiency : ndarray, shape (n,)

        Returns
        -------
        classes : ndarray of int, shape (n,)
            Negative: the C's error code.
        p_healthy : ndarray, shape (n,)
        features : ndarray, float32, shape (n, F)
        """
        x = np.ascontiguousarray(signals, np.float32)
        ph = np.ascontiguousarray(phi, np.float32)
        n, _, n_t = x.shape
        feats = np.zeros((n, self.n_features), np.float32)
        cls = np.zeros(n, np.int64)
        ph_out = np.zeros(n, np.float32)
        fp = ctypes.POINTER(ctypes.c_float)
        for i in range(n):
            p = ctypes.c_float()
            cls[i] = self.lib.swg_run_window(
                x[i].ctypes.data_as(fp), ph[i].ctypes.data_as(fp), n_t, int(op[i]),
                float(efficiency[i]), feats[i].ctypes.data_as(fp), ctypes.byref(p))
            ph_out[i] = p.value
        return cls, ph_out, feats
