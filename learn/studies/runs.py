"""One (model, input) run of the transfer comparison: its spec, estimator, fit, target-gear
adaptations and scoring.

A run names a model config (``transfer.models.<name>``, a ``_target_`` mapping as in
``conf/model/``) and an input of :data:`learn.inputs.signals.INPUTS`, and says which
target-gear adaptations it gets (:mod:`learn.transfer.study`). :func:`fit_and_adapt` fits
it on the source gears of one split and scores it and its adaptations (AdaBN or CORAL on
the held-out gear's unlabelled healthy windows; fine-tuning or MiniRocket's ridge refit on
k labelled windows per class) on the same evaluation windows. A torch net's input is
standardised once per job (:meth:`learn.learners.nets.TorchClassifier.prepare`) and
reused by its adapted copies.
"""

from __future__ import annotations

import copy
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from learn.learners.devices import resolve_device
from learn.studies.kshot import KShotSplit
from learn.studies.protocols import fit_with_groups, window_groups
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")
stacked = lazy_module("learn.learners.stacked")
log = logging.getLogger(__name__)

ADAPT = ("adabn", "coral")
FT_MODES = ("all", "last")


@dataclass
class FinetuneSettings:
    """Adaptation with k labelled target windows per class (and CORAL's ridge)."""

    modes: list[str] = field(default_factory=lambda: list(FT_MODES))  # torch nets
    steps: int = 50                 # fixed budget: no validation data exists on the target
    lr_all: float | None = None     # null: model lr / 10
    lr_last: float | None = None    # null: model lr
    replay: float = 1.0             # source windows per target window (batches, weights)
    coral_reg: float = 1.0          # CORAL's identity term


@dataclass
class RunRef:
    """A (model, input) pair named by the config, e.g. ``transfer.primary``.

    Attributes
    ----------
    model : str
        Key into the model configs (``transfer.models``).
    input : str
        One of :data:`learn.inputs.signals.INPUTS`.
    """

    model: str
    input: str

    @property
    def label(self) -> str:
        return f"{self.model}/{self.input}"


@dataclass
class RunSpec(RunRef):
    """One (model, input) run of the comparison, an entry of ``transfer.runs``.

    Attributes
    ----------
    model, input : str
        As :class:`RunRef`.
    finetune : bool
        Adapt with k labelled target windows per class (leave-one-gear-out protocols):
        torch nets are fine-tuned, MiniRocket's ridge is refitted.
    adapt : str or None
        ``adabn`` (torch nets) or ``coral`` (feature inputs), unsupervised
        (:data:`ADAPT`).
    params : dict of str to value
        Parameters set on the model for this input (e.g. ``padding_mode``).
    """

    finetune: bool = False
    adapt: str | None = None
    params: dict[str, Any] = field(default_factory=dict)


def final_step(est):
    """The classifier of a pipeline (or the estimator itself)."""
    from sklearn.pipeline import Pipeline

    return est[-1] if isinstance(est, Pipeline) else est


def pre_transform(est, X):
    """``X`` through every step of a fitted pipeline but the last."""
    from sklearn.pipeline import Pipeline

    return est[:-1].transform(X) if isinstance(est, Pipeline) and len(est) > 1 else X


def check_estimator(est, key: str):
    """``est`` (a pipeline or an estimator) after its final step's ``check_params``, when
    it has one: the settings ``fit`` would refuse, refused before any work.

    Raises
    ------
    ValueError
        One line, ``<key>: <what check_params said>``.
    """
    check = getattr(final_step(est), "check_params", None)
    if check is not None:
        try:
            check()
        except ValueError as e:
            raise ValueError(f"{key}: {e}") from None
    return est


def make_estimator(model_cfg: Mapping[str, Any], seed: int, n_aux: int,
                   params: Mapping[str, Any] | None = None):
    """Instantiate a model config (``_target_``) and set its seed, ``n_aux`` and ``params``.

    Every parameter named ``random_state`` or ``*__random_state`` is set to ``seed``,
    every ``n_aux`` to ``n_aux`` (the scalar channels of a signal input); ``params`` are
    set on the final estimator of a pipeline.
    """
    from hydra.utils import instantiate

    est = instantiate(model_cfg, _convert_="all")
    keys = est.get_params(deep=True)
    upd = {k: seed for k in keys if k == "random_state" or k.endswith("__random_state")}
    upd.update({k: n_aux for k in keys if k == "n_aux" or k.endswith("__n_aux")})
    est.set_params(**upd)
    if params:
        final_step(est).set_params(**dict(params))
    return est


def score(est, X, y, pred=None) -> tuple[float, list[tuple[str, str, int]]]:
    """Accuracy and the confusion as (true, predicted, count) triples.

    ``pred``, when given, are the estimator's predictions for ``X`` computed elsewhere
    (e.g. from cached features); ``est.predict`` is then not called.
    """
    pred = np.asarray(est.predict(X) if pred is None else pred).astype(str)
    y = np.asarray(y).astype(str)
    pairs = pd.Series(list(zip(y, pred, strict=True))).value_counts()
    return float(np.mean(pred == y)), [(t, p, int(c)) for (t, p), c in pairs.items()]


class _Scorer:
    """Collects the result rows of one (model, input) run and its adaptations."""

    def __init__(self, spec: RunSpec, X, y, evaluation, seed: int):
        self.X_eval, self.y_eval = X[evaluation], y[evaluation]
        self.base = {"model": spec.model, "input": spec.input, "seed": seed,
                     "n_test": len(evaluation)}
        self.rows: list[dict] = []

    def add(self, model: str, k: int, m, seconds: float, pred=None) -> None:
        acc, conf = score(m, self.X_eval, self.y_eval, pred)
        self.rows.append({**self.base, "model": model, "k_shot": k, "accuracy": acc,
                          "train_s": seconds, "confusion": conf})


def fit_and_adapt(spec: RunSpec, est, inp, train: np.ndarray, evaluation: np.ndarray,
                  kshot: KShotSplit | None, k_shots: Sequence[int], ft: FinetuneSettings,
                  seed: int, fitted_s: float | None = None) -> list[dict]:
    """Fit one run on the training windows, adapt it, score every variant.

    Parameters
    ----------
    spec : RunSpec
    est : estimator
        Unfitted (:func:`make_estimator`); fitted in place.
    inp : learn.inputs.signals.InputSet
        The run's input, all windows of the protocol's kind.
    train, evaluation : ndarray of int
        Rows of ``inp`` to fit on and to score on.
    kshot : KShotSplit or None
        The held-out gear's pool and unlabelled healthy windows (leave-one-gear-out); None: no
        adaptation.
    k_shots : sequence of int
        k labelled target windows per class (k > 0 fine-tuned or refitted).
    ft : FinetuneSettings
    seed : int
        Seed of the fine-tuning batches.
    fitted_s : float, optional
        ``est`` is fitted already (a torch net trained with other seeds at once,
        :func:`learn.learners.stacked.fit_seeds`), its share of that fit taking
        ``fitted_s`` seconds; not for a model whose head is refitted (MiniRocket).

    Returns
    -------
    list of dict
        One row per scored variant (model, input, seed, n_test, model name with its
        adaptation, k_shot, accuracy, train_s [s], confusion as (true, predicted, count)).

    Raises
    ------
    ValueError
        ``fitted_s`` given for a run whose head is refitted.
    """
    X, y = inp.X, inp.y
    net = final_step(est)
    refit = kshot is not None and spec.finetune and hasattr(net, "refit_head")
    if refit and fitted_s is not None:
        raise ValueError(f"{spec.label}: a refitted head needs its training features; fit "
                         "it here (fitted_s=None)")
    t0 = time.perf_counter() - (fitted_s or 0.0)
    if refit:  # MiniRocket: the training features, kept for the ridge refits
        f_src = est.fit_transform(X[train], y[train])
    elif fitted_s is None:
        fit_with_groups(est, X[train], y[train], window_groups(inp.meta)[train])
    fit_s = time.perf_counter() - t0
    sc = _Scorer(spec, X, y, evaluation, seed)
    sc.X_eval = _prepared(est, sc.X_eval)  # once for the run and its adaptations
    f_eval = net.transform(pre_transform(est, sc.X_eval)) if refit else None  # MiniRocket
    sc.add(spec.model, 0, est, fit_s, None if f_eval is None else net.ridge_.predict(f_eval))
    if kshot is None:
        return sc.rows
    _adapt_unsupervised(sc, spec, est, X, y, train, kshot, ft)
    if not spec.finetune:
        return sc.rows
    ks = [k for k in k_shots if k > 0]
    if refit:  # MiniRocket: the ridge only, on the features computed above
        _refit_heads(sc, spec, est, X, y, train, f_src, f_eval, kshot, ks, ft)
    else:
        _fine_tune(sc, spec, est, X, y, train, kshot, ks, ft, seed)
    return sc.rows


def fit_at_once(spec: RunSpec, model_cfg: Mapping[str, Any], inp, train: np.ndarray,
                seeds: Sequence[int]) -> list | None:
    """A run's torch net fitted for every seed at once on the training rows
    (:func:`learn.learners.stacked.fit_seeds`), to pass to :func:`fit_and_adapt`.

    Parameters
    ----------
    spec : RunSpec
    model_cfg : mapping
        The run's model config (``_target_``), as :func:`make_estimator` takes it.
    inp : learn.inputs.signals.InputSet
        The run's input, all windows of the protocol's kind.
    train : ndarray of int
        Rows of ``inp`` to fit on (the same for every seed: one split).
    seeds : sequence of int
        ``random_state`` of each copy.

    Returns
    -------
    list of TorchClassifier or None
        One fitted copy per seed, in order (a one-step pipeline stays one); None for one
        seed or a run that is not a torch net alone (one with a scaler before it, say):
        those are fitted seed by seed.
    """
    from sklearn.pipeline import Pipeline

    est = make_estimator(model_cfg, int(seeds[0]), inp.n_aux, spec.params)
    net = est[0] if isinstance(est, Pipeline) and len(est) == 1 else est
    if len(seeds) < 2 or not isinstance(net, stacked.TorchClassifier):
        return None
    nets = stacked.fit_seeds(net, inp.X[train], inp.y[train], [int(s) for s in seeds],
                             window_groups(inp.meta)[train])
    return [n if net is est else Pipeline([(est.steps[0][0], n)]) for n in nets]


def net_device_settings(runs: Sequence[RunRef], models: Mapping[str, Any]) -> dict[str, Any]:
    """The ``torch.device`` of each torch net of ``runs`` (a model of ``models`` with a
    ``device`` parameter), resolved on this machine
    (:func:`learn.learners.devices.resolve_device`; the jobs' workers resolve it alike).

    Raises
    ------
    ValueError
        One line naming ``transfer.models.<name>.estimator.device``: a setting outside
        :data:`learn.learners.devices.DEVICE_CHOICES`, or a CUDA device on a machine
        without one.
    """
    out = {}
    for name in dict.fromkeys(r.model for r in runs):
        params = final_step(make_estimator(models[name], 0, 0)).get_params(deep=False)
        if "device" in params:
            out[name] = resolve_device(params["device"],
                                       f"transfer.models.{name}.estimator.device")
    return out


def _prepared(est, X):
    """``X`` as a fitted torch net reads it (:meth:`learn.learners.nets.TorchClassifier.prepare`:
    checked, standardised, a tensor), which its fine-tuned and AdaBN copies reuse; ``X``
    itself for other models and for pipelines with steps before the net."""
    from sklearn.pipeline import Pipeline

    net = final_step(est)
    alone = not isinstance(est, Pipeline) or len(est) == 1
    return net.prepare(X) if alone and hasattr(net, "prepare") else X


def _adapt_unsupervised(sc: _Scorer, spec: RunSpec, est, X, y, train, kshot: KShotSplit,
                        ft: FinetuneSettings) -> None:
    """AdaBN (torch nets) or CORAL (feature models) on the held-out gear's unlabelled
    healthy windows (``kshot.unlabelled``, labels unused)."""
    if spec.adapt == "adabn":
        if not hasattr(final_step(est), "adapt_bn"):
            raise ValueError(f"{spec.label}: AdaBN needs a torch net")
        t0 = time.perf_counter()
        m = copy.deepcopy(est)
        final_step(m).adapt_bn(pre_transform(m, X[kshot.unlabelled]))
        sc.add(f"{spec.model}+adabn", 0, m, time.perf_counter() - t0)
    elif spec.adapt == "coral":
        from learn.learners.adapt import CoralClassifier

        if X.ndim != 2:
            raise ValueError(f"{spec.label}: CORAL needs a feature input")
        t0 = time.perf_counter()
        m = CoralClassifier(est, reg=float(ft.coral_reg))
        m.fit(X[train], y[train], X[kshot.unlabelled])
        sc.add(f"{spec.model}+coral", 0, m, time.perf_counter() - t0)


def _refit_heads(sc: _Scorer, spec: RunSpec, est, X, y, train, f_src: np.ndarray,
                 f_eval: np.ndarray, kshot: KShotSplit, ks: Sequence[int],
                 ft: FinetuneSettings) -> None:
    """MiniRocket: the ridge refitted on k shots per class, on the kernel features of the
    training windows (``f_src``, from the fit) and of the evaluation windows (``f_eval``)."""
    for k in ks:
        shots = kshot.shots(k)
        t0 = time.perf_counter()
        m = copy.deepcopy(est)
        final_step(m).refit_head(pre_transform(m, X[shots]), y[shots], y_source=y[train],
                                 source_features=f_src, replay=float(ft.replay))
        sc.add(f"{spec.model}+ft_head", k, m, time.perf_counter() - t0,
               final_step(m).ridge_.predict(f_eval))


def _fine_tune(sc: _Scorer, spec: RunSpec, est, X, y, train, kshot: KShotSplit,
               ks: Sequence[int], ft: FinetuneSettings, seed: int) -> None:
    """Torch nets: fine-tuned on k shots per class, all layers and the last layer."""
    if not hasattr(final_step(est), "fine_tune"):
        raise ValueError(f"{spec.label}: k-shot adaptation needs a torch net or MiniRocket")
    replay = float(ft.replay)
    x_src = _prepared(est, X[train]) if replay > 0 else None  # once for every mode and k
    for mode in ft.modes:
        for k in ks:
            shots = kshot.shots(k)
            t0 = time.perf_counter()
            m = copy.deepcopy(est)
            lr = getattr(ft, f"lr_{mode}")
            final_step(m).fine_tune(
                pre_transform(m, X[shots]), y[shots], mode=mode, steps=int(ft.steps),
                lr=None if lr is None else float(lr),
                X_replay=pre_transform(m, x_src) if replay > 0 else None,
                y_replay=y[train] if replay > 0 else None, replay=replay,
                random_state=seed * 1000 + k)
            sc.add(f"{spec.model}+ft_{mode}", k, m, time.perf_counter() - t0)


class JobProgress:
    """One progress line over every job of the comparison, all data sets together: jobs
    done, jobs left and the time left estimated from the mean time per finished job; a
    log line per finished job (its data set, protocol, split and seed, the wall time of
    each run and their accuracies at k = 0).

    Parameters
    ----------
    total : int
        Jobs planned (:func:`learn.transfer.study.planned_jobs` summed over the data
        sets); corrected with :meth:`adjust` when a data set turns out to have other
        splits.
    enabled : bool
        Show the progress line (the log lines are written either way).
    """

    def __init__(self, total: int, enabled: bool = True):
        from tqdm.auto import tqdm

        self.total, self.done, self.t0 = int(total), 0, time.perf_counter()
        self.bar = tqdm(total=self.total, desc="transfer", unit="job", smoothing=0.0,
                        disable=not enabled, bar_format=(
                            "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} jobs "
                            "done{postfix} [{elapsed}, about {remaining} left]"))

    def adjust(self, delta: int) -> None:
        """Change the number of planned jobs by ``delta`` (a skipped protocol, a data set
        with more or fewer splits than planned)."""
        if delta:
            self.total += int(delta)
            self.bar.total = self.total
            self.bar.refresh()

    def finished(self, dataset: str, cell: tuple, seconds: Mapping[str, tuple],
                 rows: Sequence[dict]) -> None:
        """Count one finished job ``cell`` = (protocol, split, seed) and log it;
        ``seconds``: run label -> (wall, CPU) [s], ``rows``: its result rows."""
        self.done += 1
        left = max(self.total - self.done, 0)
        elapsed = time.perf_counter() - self.t0
        protocol, split, seed = cell[0], cell[1].name, cell[2]
        acc = {f"{r['model']}/{r['input']}": round(r["accuracy"], 4) for r in rows
               if r["k_shot"] == 0}
        log.info("job %d/%d done, %d left (about %.1f min): %s %s %s seed %d in %.1f s; "
                 "run seconds %s; accuracy at k = 0 %s", self.done, self.total, left,
                 elapsed / self.done * left / 60, dataset, protocol, split, seed,
                 sum(v[0] for v in seconds.values()),
                 {k: round(v[0], 1) for k, v in seconds.items()}, acc)
        self.bar.set_postfix_str(f"{left} left ({dataset})", refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()
