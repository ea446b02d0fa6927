"""Diagnosis models on disk in a format that cannot run code, with a model card.

A pickle (joblib) runs whatever code it names when it is opened: a model file handed to a
user could do anything on their machine before any check. A diagnosis model is therefore
written with skops' secure persistence (:func:`skops.io.dump`: the scikit-learn estimators
as their state, no code) as ``<name>.skops``, and beside it a small JSON *model card*
``<name>.card.json``: what the model knows (classes, health features, sample rate,
window), what made it (the training data sets' names and config hashes, the commit, the
library versions) and the file's SHA-256. :func:`load_model` checks the card and the hash,
then loads only the types a diagnosis model holds (:data:`TRUSTED`); any other type, a
changed file or a card of another file is refused in one line naming the file. A legacy
pickle is refused unless the caller trusts it explicitly (``trust_pickle``).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np

from learn.inputs.health import feature_names
from swgmon.assessment.model import DiagnosisModel
from swgsim.base.lazy import lazy_module
from swgsim.files.digest import sha256_file
from swgsim.files.inputs import check_input_file
from swgsim.files.ownership import atomic_write_bytes, atomic_write_json
from swgsim.files.provenance import git_revision, library_versions, package_version

sio = lazy_module("skops.io")

__all__ = ["CARD_SUFFIX", "MODEL_SUFFIX", "TRUSTED", "load_model", "model_card", "save_model"]

MODEL_SUFFIX = ".skops"
CARD_SUFFIX = ".card.json"
CARD_VERSION = 1
#: Most bytes a model file's zip members may unpack to: a diagnosis model of the monitor
#: evaluation is about 1.6 MiB in some 1000 members; a 1.1 MB zip bomb with a matching
#: card unpacked to 2.8 GB before it was refused (issue 43).
MAX_UNPACKED_BYTES = 256 * 2**20
#: Most members of a model file's zip (each one an allocation when it is read).
MAX_MEMBERS = 100_000
#: The types a diagnosis model's file may hold (its classifier, regressors and their
#: parts); anything else is refused by :func:`load_model`.
TRUSTED = [
    "sklearn.ensemble._hist_gradient_boosting.gradient_boosting.HistGradientBoostingClassifier",
    "sklearn.ensemble._hist_gradient_boosting.gradient_boosting.HistGradientBoostingRegressor",
    "sklearn.ensemble._hist_gradient_boosting.predictor.TreePredictor",
    "sklearn.ensemble._hist_gradient_boosting.binning._BinMapper",
    "sklearn._loss.loss.HalfMultinomialLoss", "sklearn._loss.loss.HalfSquaredError",
    "sklearn._loss.loss.HalfBinomialLoss", "sklearn._loss.link.MultinomialLogit",
    "sklearn._loss.link.IdentityLink", "sklearn._loss.link.LogitLink",
    "sklearn._loss.link.Interval", "numpy.dtype", "builtins.float", "builtins.int",
    "builtins.tuple", "collections.OrderedDict",
]


def _curves(reading: dict) -> dict:
    return {f: [np.asarray(lv, float).tolist(), np.asarray(rd, float).tolist()]
            for f, (lv, rd) in reading.items()}


def _state(model: DiagnosisModel, without: bool = False) -> dict:
    """The model as plain data and estimators (no class of this project); ``without``:
    with the severity regressors and curves without each training gear."""
    return {"classes": list(model.classes), "classifier": model.classifier,
            "severity": {f: [reg, [float(q[0]), float(q[1])]]
                         for f, (reg, q) in model.severity.items()},
            "reading": _curves(model.reading),
            **({"severity_without": {str(g): dict(r) for g, r in
                                     model.severity_without.items()},
                "reading_without": {str(g): _curves(r) for g, r in
                                    model.reading_without.items()}} if without else {}),
            "points_range": None if model.points_range is None
            else np.asarray(model.points_range, float).tolist(),
            "n_features": int(model.n_features), "sample_rate_hz": float(model.sample_rate_hz),
            "window_s": float(model.window_s)}


def model_card(model: DiagnosisModel, training: list[dict], path: Path) -> dict:
    """The card of a model file (module docstring).

    Parameters
    ----------
    model : DiagnosisModel
    training : list of dict
        The training data sets: ``name``, ``config_hash`` (and ``path`` and
        ``manifest_sha256`` for one on disk), ``gears``.
    path : Path
        The model file, written already (its SHA-256 goes into the card).
    """
    twist = model.n_features > len(feature_names())
    return {"card_version": CARD_VERSION, "file": path.name, "sha256": sha256_file(path),
            "format": "skops", "classes": list(model.classes),
            "features": feature_names(twist=twist)[:model.n_features or None],
            "sample_rate_hz": float(model.sample_rate_hz), "window_s": float(model.window_s),
            "operating_points_range": None if model.points_range is None
            else np.asarray(model.points_range, float).tolist(),
            "training": training, "commit": git_revision(), "package_version":
            package_version(), "library_versions": library_versions()}


def save_model(model: DiagnosisModel, path: str | os.PathLike, training: list[dict],
               without: bool = False) -> Path:
    """Write a diagnosis model as ``<path>.skops`` and its card ``<path>.card.json``,
    atomically (in a claimed folder, both listed in its ownership stamp); return the
    model file's path (the suffix added when ``path`` lacks it). ``without``: with the
    severity regressors without each training gear (:meth:`DiagnosisModel.without`: the
    prognosis's cross-validation; a file as many times larger)."""
    p = Path(path)
    p = p if p.suffix == MODEL_SUFFIX else p.with_name(p.name + MODEL_SUFFIX)
    atomic_write_bytes(p, sio.dumps(_state(model, without)))
    atomic_write_json(_card_path(p), model_card(model, training, p))
    return p


def _card_path(p: Path) -> Path:
    return p.with_name(p.name.removesuffix(MODEL_SUFFIX) + CARD_SUFFIX)


def load_model(path: str | os.PathLike, key: str = "diagnosis_model",
               trust_pickle: bool = False) -> DiagnosisModel:
    """A diagnosis model written by :func:`save_model`, checked before it is trusted.

    Parameters
    ----------
    path : path-like
        The ``.skops`` file; a legacy ``.joblib`` pickle only with ``trust_pickle``.
    key : str
        The option that named it, for messages.
    trust_pickle : bool
        Open a pickle: it runs any code it names when opened; only for a file you made
        yourself.

    Raises
    ------
    FileNotFoundError
        No file.
    ValueError
        One line naming the file: not a regular file of a bounded size, a pickle without
        ``trust_pickle``, no card or a card of another file, a SHA-256 that does not match
        the card, a zip that unpacks to more than :data:`MAX_UNPACKED_BYTES`, a type a
        diagnosis model does not hold, classes other than its card's, or parts that are
        not a diagnosis model's (:meth:`DiagnosisModel.check`).
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(2, f"{key}: no diagnosis model (swgsim-train "
                                   "experiment=monitor writes reports/monitor/models/*.skops)",
                                str(p))
    check_input_file(p, key)
    if p.suffix != MODEL_SUFFIX:
        return _pickle(p, key, trust_pickle)
    card = _read_card(p, key)
    data = p.read_bytes()  # read once: the hash checked is that of the bytes loaded
    if hashlib.sha256(data).hexdigest() != card.get("sha256"):
        raise ValueError(f"{key}: {p} does not match its card {_card_path(p).name} "
                         "(SHA-256 differs: the file was changed or replaced)")
    _check_unpacked(data, p, key)
    try:
        untrusted = sorted(set(sio.get_untrusted_types(data=data)) - set(TRUSTED))
    except Exception as e:  # noqa: BLE001 - any unreadable file is the same answer
        raise ValueError(f"{key}: {p} is not a skops file ({type(e).__name__})") from None
    if untrusted:
        raise ValueError(f"{key}: {p} holds types a diagnosis model does not: "
                         f"{', '.join(untrusted[:3])}; refused (no code is loaded)")
    state = sio.loads(data, trusted=TRUSTED)
    return _model(state, p, key, card.get("classes", []))


def _check_unpacked(data: bytes, p: Path, key: str) -> None:
    """Refuse a ``.skops`` zip whose members unpack to more than
    :data:`MAX_UNPACKED_BYTES` (the sizes its directory declares, which bound what
    :mod:`zipfile` inflates), before any member is inflated."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            infos = z.infolist()
    except (zipfile.BadZipFile, OSError, ValueError) as e:
        raise ValueError(f"{key}: {p} is not a skops file ({type(e).__name__})") from None
    total = sum(i.file_size for i in infos)
    if total > MAX_UNPACKED_BYTES or len(infos) > MAX_MEMBERS:
        raise ValueError(f"{key}: {p} unpacks to {total / 2**20:.1f} MiB in {len(infos)} "
                         f"members, over the {MAX_UNPACKED_BYTES / 2**20:g} MiB and "
                         f"{MAX_MEMBERS} members a diagnosis model is allowed; refused")


def _read_card(p: Path, key: str) -> dict:
    c = _card_path(p)
    try:
        check_input_file(c, key, max_bytes=1 << 20)
        card = json.loads(c.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise ValueError(f"{key}: {p} has no readable model card {c.name} ({e}); a model "
                         "is loaded only with its card") from None
    if not isinstance(card, dict) or card.get("file") != p.name:
        raise ValueError(f"{key}: the card {c.name} is not that of {p.name}")
    return card


def _read(curves: dict) -> dict:
    return {f: (np.asarray(v[0], float), np.asarray(v[1], float)) for f, v in curves.items()}


def _model(state, p: Path, key: str, card_classes: list) -> DiagnosisModel:
    """The model of a loaded state, checked part by part (:meth:`DiagnosisModel.check`)
    and against its card's classes."""
    try:
        m = DiagnosisModel(list(state["classes"]), state["classifier"],
                           {f: (v[0], (float(v[1][0]), float(v[1][1])))
                            for f, v in state["severity"].items()},
                           None if state["points_range"] is None
                           else np.asarray(state["points_range"], float),
                           int(state["n_features"]), float(state["sample_rate_hz"]),
                           float(state["window_s"]),
                           _read(state.get("reading", {})),
                           {int(g): dict(r) for g, r in
                            state.get("severity_without", {}).items()},
                           {int(g): _read(r) for g, r in
                            state.get("reading_without", {}).items()})
    except (KeyError, TypeError, IndexError, ValueError):
        raise ValueError(f"{key}: {p} is not a diagnosis model") from None
    if m.classes != list(card_classes):
        raise ValueError(f"{key}: {p} holds classes {m.classes} where its card lists "
                         f"{list(card_classes)}")
    return m.check(f"{key}: {p}")


def _pickle(p: Path, key: str, trust: bool) -> DiagnosisModel:
    if not trust:
        raise ValueError(f"{key}: {p} is a pickle, which runs any code it names when it is "
                         "opened; refused. Use a .skops model of swgsim-train "
                         "experiment=monitor, or pass trust_pickle=true for a file you made")
    import joblib  # a pickle the user chose to trust

    try:
        m = joblib.load(p)
    except Exception as e:  # noqa: BLE001 - any unpickling failure is the same answer
        raise ValueError(f"{key}: {p} is not a diagnosis model ({type(e).__name__})") from None
    if not isinstance(m, DiagnosisModel):
        raise ValueError(f"{key}: {p} holds a {type(m).__name__}, not a diagnosis model")
    for name in ("reading", "reading_without"):  # pickled before the reading curve
        vars(m).setdefault(name, {})
    return m.check(f"{key}: {p}")
