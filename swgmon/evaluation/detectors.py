"""Per-window detectors beside the monitor: classifiers used as monitors, in a registry.

Each labels every window on its own and raises an alarm whenever one window is classified
as anything but healthy (the way a per-window classifier is used as a monitor). The
registry :data:`DETECTORS` holds them by name, like the faults
(:func:`swgsim.gear.faults.register_fault`) and the models
(:func:`learn.learners.models.register_model`); an evaluation runs the ones its config
names (``monitor.study.detectors``). Shipped:

``paper_rf``
    The paper's pipeline (Sec. III-IV): the random forest of
    :mod:`learn.learners.models` (``rf``) on the Table III Selection 1 features, every
    window normalised by *one* reference window of its gear and operating point (eq. 7) -
    here the gear's first commissioning window at that operating point.
``cnn_res``
    The best per-window classifier of the transfer study (``conf/experiment/transfer.yaml``):
    the 1D-CNN on the synchronous residual (``raw_res``, :mod:`learn.inputs.signals`)
    against the same one reference window, with its efficiency scalars, as run there
    (three circular conv blocks, ten epochs).

Both are trained on the same lives of the training gears as the monitor's diagnosis model
(:func:`.training.training_lives`), class-balanced as the paper's data set
(every class drawn down to the smallest's count), and know the same classes. Their inputs
are defined at a steady input speed: on a data set along an operating profile they cannot
run (:meth:`DetectorSpec.cannot_run_on` says why, and the evaluation reports it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from learn.inputs.signals import AUX, build_input
from learn.learners.models import make_model, make_pipeline
from swgmon.assessment.model import HEALTHY
from swgsim.base.registry import Registry
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import DatasetPlan
from swgsim.datasets.schema import PER_SAMPLE, make_dataset


@dataclass(frozen=True)
class DetectorSpec:
    """A per-window detector: its input and how to make its untrained estimator.

    Attributes
    ----------
    input : str
        An input of :func:`learn.inputs.signals.build_input` (e.g. ``sel1``, ``raw_res``),
        each window against one reference window of its operating point.
    make : callable
        ``make(seed, device) -> estimator`` with ``fit(x, y)`` and ``predict(x)`` (class
        names); ``device`` a resolved torch device string (``cpu``, ``cuda:0``), used by
        a torch net and ignored by the others.
    source : str
        Where the detector comes from (paper section, study).
    steady_only : bool
        Its input is defined at a steady input speed (a window at one operating point).
    uses_device : bool
        A torch net, run on ``monitor.device``.
    """

    input: str
    make: Callable[[int, str], object]
    source: str
    steady_only: bool = True
    uses_device: bool = False

    def cannot_run_on(self, plan: DatasetPlan) -> str | None:
        """Why this detector cannot run on a data set's lives, or None if it can."""
        if self.steady_only and plan.profile is not None:
            return (f"its input {self.input} is defined at a steady input speed; "
                    f"{plan.config.name} moves along an operating profile")
        return None


def _paper_rf(seed: int, device: str):  # noqa: ARG001 - no torch net
    return make_model("rf", random_state=seed)


def _cnn_res(seed: int, device: str):
    from learn.learners.nets import CNN1DClassifier  # torch, imported when a net is made

    net = CNN1DClassifier(channels=(32, 64, 64), kernel_sizes=(7, 5, 5), strides=(2, 2, 2),
                          padding_mode="circular", n_aux=len(AUX), max_epochs=10,
                          device=device, random_state=seed)  # monitor.device, resolved
    return make_pipeline(net, name="cnn")


#: The per-window detectors by name (module docstring); add one with
#: :func:`register_detector`.
DETECTORS: Registry[DetectorSpec] = Registry("detector", __name__, "DETECTORS", {
    "paper_rf": DetectorSpec("sel1", _paper_rf, "paper Sec. III, Table III selection 1"),
    "cnn_res": DetectorSpec("raw_res", _cnn_res, "transfer study, CNN on raw_res",
                            uses_device=True),
}.items())


def register_detector(name: str, spec: DetectorSpec) -> None:
    """Add a per-window detector to :data:`DETECTORS`, to be named in
    ``monitor.study.detectors``.

    Parameters
    ----------
    name : str
        Its name in the evaluation's tables (not ``monitor``, ``per_window`` or
        ``always``, the rows the evaluation always has).
    spec : DetectorSpec

    Raises
    ------
    ValueError
        A name already registered or reserved.
    """
    if name in DETECTORS or name in ("monitor", "per_window", "always"):
        raise ValueError(f"detector {name!r} is already registered or reserved")
    DETECTORS.add(name, spec)


@dataclass
class References:
    """One reference window per operating point of a gear: its first commissioning window
    there (paper eq. 7's "value of the healthy gear").

    Attributes
    ----------
    signal : ndarray, float32, shape (R, 5, n_t)
        Bridge outputs [mV/V].
    meta : dict of ndarray, shape (R,)
        The schema's per-sample variables, ``reference`` True.
    """

    signal: np.ndarray
    meta: dict[str, np.ndarray]

    @classmethod
    def of(cls, sim: LifeSimulator, n_commissioning: int) -> References:
        """The references of a life's gear from its first ``n_commissioning`` windows.

        Raises
        ------
        ValueError
            If an operating point of the duty cycle has no commissioning window.
        """
        duty = sim.schedule.duty_index[:n_commissioning]
        points, first = np.unique(duty, return_index=True)
        if points.size != len(sim.schedule.duty):
            raise ValueError(f"commissioning ({n_commissioning} windows) visits "
                             f"{points.size} of {len(sim.schedule.duty)} operating points")
        sig, meta = zip(*(sim.windows(int(i), int(i) + 1) for i in first), strict=True)
        meta = {k: np.concatenate([m[k] for m in meta]) for k in meta[0]}
        meta["reference"][:] = True
        return cls(np.concatenate(sig), meta)


def window_inputs(kind: str, signal: np.ndarray, meta: dict[str, np.ndarray],
                  refs: References, sample_rate_hz: float) -> np.ndarray:
    """A detector's input for windows of a stream, each against its reference.

    Parameters
    ----------
    kind : str
        An input of :func:`learn.inputs.signals.build_input`.
    signal : ndarray, shape (n, 5, n_t)
        Bridge outputs [mV/V] (:meth:`swgsim.datasets.life.LifeSimulator.windows`).
    meta : dict of ndarray, shape (n,)
        Their metadata, same source.
    refs : References
    sample_rate_hz : float

    Returns
    -------
    ndarray, float32
        (n, F) or (n, C, T), in window order.
    """
    both = {k: np.concatenate([refs.meta[k], meta[k]]) for k in PER_SAMPLE}
    both["reference"] = np.r_[np.ones(len(refs.signal), bool), np.zeros(len(signal), bool)]
    ds = make_dataset(np.concatenate([refs.signal, signal]),
                      np.arange(signal.shape[-1]) / sample_rate_hz, both)
    return build_input(ds, kind).X


@dataclass
class WindowClassifier:
    """A trained per-window detector.

    Attributes
    ----------
    name : str
        Key of :data:`DETECTORS`.
    estimator : object
        Fitted scikit-learn pipeline.
    classes : list of str
        Healthy first, as the diagnosis model's.
    """

    name: str
    estimator: object
    classes: list[str] = field(default_factory=list)

    @property
    def input(self) -> str:
        """The detector's input (:attr:`DetectorSpec.input`)."""
        return DETECTORS[self.name].input

    def labels(self, x: np.ndarray) -> np.ndarray:
        """Index into :attr:`classes` of each window's predicted class, shape (n,)."""
        pred = np.asarray(self.estimator.predict(x)).astype(str)
        lookup = {c: i for i, c in enumerate(self.classes)}
        return np.array([lookup[c] for c in pred], dtype=np.int64)


def fit_detector(name: str, x: np.ndarray, y: np.ndarray, classes: list[str],
                 seed: int = 0, device: str = "cpu") -> WindowClassifier:
    """Train detector ``name`` on inputs ``x`` (n, ...) and class names ``y`` (n,), a
    torch net on ``device`` (resolved: ``cpu``, ``cuda:0``; ``monitor.device``).

    Raises
    ------
    ValueError
        ``classes`` not starting with healthy.
    """
    if classes[0] != HEALTHY:
        raise ValueError(f"classes must start with {HEALTHY!r}, got {classes[:1]}")
    est = DETECTORS[name].make(seed, device)
    est.fit(x, y)
    return WindowClassifier(name, est, list(classes))


__all__ = ["DETECTORS", "DetectorSpec", "References", "WindowClassifier", "fit_detector",
           "register_detector", "window_inputs"]
