"""Where the torch nets run, and what a run records about it.

One place for the device setting of the nets and their arithmetic (``device`` of
:class:`learn.learners.nets.TorchClassifier`, ``monitor.device`` of the monitor's CNN
detector): its check, its choice on this machine, its name and what a run records.

Torch is imported by the functions that need a :class:`torch.device`, never at import of
this module (:mod:`swgcli.schema` reaches the configs that name a device).

Determinism: on the CPU, torch's kernels give the same numbers for the same inputs and
the same number of threads; on a CUDA GPU only with
``torch.use_deterministic_algorithms(True)`` and cuDNN's deterministic, non-benchmarking
mode (and ``CUBLAS_WORKSPACE_CONFIG`` set); the project sets neither, so a GPU run records
``deterministic = False`` unless the caller switched them on
(https://pytorch.org/docs/stable/notes/randomness.html).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import torch

#: The device settings a config may give: "cpu", "cuda" (the first GPU), "cuda:N" (GPU
#: N) or "auto" (the first GPU where CUDA is present, else the CPU).
DEVICE_CHOICES = ("cpu", "cuda", "cuda:N", "auto")
_DEVICE = re.compile(r"(cpu|cuda|cuda:\d+|auto)")


def check_device(value: object, key: str) -> str:
    """Refuse a device setting that is none of :data:`DEVICE_CHOICES`, without torch.

    Parameters
    ----------
    value : object
        The setting, e.g. ``"cpu"``, ``"cuda:1"``, ``"auto"``.
    key : str
        Config key named in the message (e.g. ``monitor.device``).

    Returns
    -------
    str
        The setting.

    Raises
    ------
    ValueError
        One line naming ``key`` and the allowed values.
    """
    if not isinstance(value, str) or not _DEVICE.fullmatch(value):
        raise ValueError(f"{key}: must be one of {', '.join(DEVICE_CHOICES)} (N a GPU "
                         f"index), got {value!r}")
    return value


def resolve_device(value: str = "auto", key: str = "device") -> torch.device:
    """The device a setting gives on this machine, refused in one line if it has none.

    Parameters
    ----------
    value : str
        One of :data:`DEVICE_CHOICES`; ``"auto"``: ``cuda`` where CUDA is available, else
        ``cpu``.
    key : str
        Config key named in messages.

    Returns
    -------
    torch.device

    Raises
    ------
    ValueError
        A setting outside :data:`DEVICE_CHOICES` (:func:`check_device`); ``cuda`` or
        ``cuda:N`` on a machine without CUDA, or N beyond its GPUs.
    """
    import torch

    check_device(value, key)
    if value == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    dev = torch.device(value)
    if dev.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(f"{key}={value}: this machine has no CUDA GPU (torch "
                             f"{torch.__version__}, CUDA {torch.version.cuda or 'not built'}); "
                             f"use {key}=cpu or {key}=auto")
        n = torch.cuda.device_count()
        if dev.index is not None and dev.index >= n:
            raise ValueError(f"{key}={value}: this machine has {n} CUDA GPU(s), "
                             f"cuda:0 to cuda:{n - 1}")
    return dev


#: Arithmetic of the forward passes (:class:`learn.learners.nets.TorchClassifier`, ``precision``).
PRECISIONS = ("float32", "bfloat16", "auto")


def resolve_precision(precision: str, device: torch.device) -> str:
    """The arithmetic a ``precision`` setting gives on ``device``: ``"auto"`` is bfloat16
    where the hardware has fast bfloat16 kernels (a CUDA GPU that supports it; a CPU
    with AVX-512, whose oneDNN kernels run bfloat16), else float32; the others are
    themselves.

    Raises
    ------
    ValueError
        For a setting not in :data:`PRECISIONS`.
    """
    import torch

    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {PRECISIONS}, got {precision!r}")
    if precision != "auto":
        return precision
    if device.type == "cuda":
        return "bfloat16" if torch.cuda.is_bf16_supported() else "float32"
    fast = device.type == "cpu" and torch.backends.cpu.get_cpu_capability().startswith("AVX512")
    return "bfloat16" if fast else "float32"


def device_label(device: torch.device | str) -> str:
    """``cpu``, or ``cuda:<index> (<the GPU's name>)``.

    Parameters
    ----------
    device : torch.device or str
        A resolved device (not ``"auto"``).

    Returns
    -------
    str
    """
    import torch

    dev = torch.device(device)
    if dev.type != "cuda":
        return dev.type
    index = dev.index if dev.index is not None else torch.cuda.current_device()
    return f"cuda:{index} ({torch.cuda.get_device_name(index)})"


def device_record(device: torch.device | str) -> dict[str, str | int | bool]:
    """What a run records about where its nets ran (MLflow params, report).

    Parameters
    ----------
    device : torch.device or str
        A resolved device (not ``"auto"``).

    Returns
    -------
    dict
        ``device`` (:func:`device_label`), ``torch_threads`` (``torch.get_num_threads()``
        now), ``deterministic_algorithms`` (``torch.are_deterministic_algorithms_enabled()``),
        ``cudnn_deterministic``, ``cudnn_benchmark`` (``torch.backends.cudnn``) and
        ``deterministic``: True on the CPU; on a GPU only with deterministic algorithms
        on, cuDNN deterministic and not benchmarking (module docstring).
    """
    import torch

    dev = torch.device(device)
    algorithms = bool(torch.are_deterministic_algorithms_enabled())
    cudnn_det = bool(torch.backends.cudnn.deterministic)
    cudnn_bench = bool(torch.backends.cudnn.benchmark)
    deterministic = dev.type == "cpu" or (algorithms and cudnn_det and not cudnn_bench)
    return {"device": device_label(dev), "torch_threads": int(torch.get_num_threads()),
            "deterministic": deterministic, "deterministic_algorithms": algorithms,
            "cudnn_deterministic": cudnn_det, "cudnn_benchmark": cudnn_bench}


def net_record(estimator) -> dict[str, str | int | bool]:
    """:func:`device_record` of an estimator's torch net, or an empty dict for none.

    Parameters
    ----------
    estimator : estimator or scikit-learn Pipeline
        Its final step is a torch net if it has a ``device`` parameter; its device is
        the fitted ``device_`` where fitted, else the setting resolved on this machine.

    Returns
    -------
    dict
        The record (MLflow params of a run with a torch net); empty for any other model.

    Raises
    ------
    ValueError
        An unfitted net's ``device`` that this machine does not have (:func:`resolve_device`).
    """
    final = estimator.steps[-1][1] if hasattr(estimator, "steps") else estimator
    get = getattr(final, "get_params", None)
    if get is None or "device" not in get(deep=False):
        return {}
    fitted = getattr(final, "device_", None)
    return device_record(fitted if fitted is not None else resolve_device(final.device))


__all__ = ["DEVICE_CHOICES", "PRECISIONS", "check_device", "device_label", "device_record",
           "net_record", "resolve_device", "resolve_precision"]
