"""Torch MLP and 1D-CNN classifiers behind the scikit-learn interface.

One small wrapper (:class:`TorchClassifier`) instead of skorch: the transfer study also
fine-tunes (:meth:`TorchClassifier.fine_tune`), re-estimates the batch-norm statistics on
unlabelled target windows (AdaBN, :meth:`TorchClassifier.adapt_bn`) and reads the
penultimate embedding (:meth:`TorchClassifier.embed`). ``random_state`` seeds everything
through local generators (``torch.random.fork_rng``), never the global seed.

Input ``X``: (n, C, T) signals whose last ``n_aux`` channels are per-window scalars held
constant along time (:mod:`learn.inputs.signals`), or (n, F) features, standardised per
channel (per feature) with the training windows' statistics, which a fine-tuned model
keeps. Device: :func:`learn.learners.devices.resolve_device`; CPU threads are the
caller's (``torch.set_num_threads``); several seeds at once on a GPU:
:func:`learn.learners.stacked.fit_seeds` (``docs/learners_transfer.md``, "The learners").
Input checks are scikit-learn's (``validate_data``); the classifiers pass
``check_estimator`` (``tests/learn/test_estimator_checks.py``, 2-D data only).
"""

from __future__ import annotations

import contextlib
import copy
import logging
import math

import numpy as np
import torch
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from torch import nn

from .devices import check_device, resolve_device, resolve_precision
from .torch_modules import CNN1DNet, MLPNet

log = logging.getLogger(__name__)

@contextlib.contextmanager
def _local_seed(seed: int, device: torch.device):
    """Seed torch's generators in the block only (``fork_rng``): reproducible init, dropout."""
    devices = [device.index or 0] if device.type == "cuda" else []
    with torch.random.fork_rng(devices=devices):
        torch.manual_seed(seed)
        yield


def _seed_of(random_state) -> int:
    if random_state is None or isinstance(random_state, np.random.Generator):
        return int(np.random.default_rng(random_state).integers(2**31 - 1))
    return int(random_state)


def rows(t: torch.Tensor, idx: torch.Tensor) -> torch.Tensor:
    """Rows ``idx`` (k,) of ``t`` (n, ...), shape (k, ...): ``t[idx]`` by ``index_select``
    (256 rows of 6000: 0.2 against 1.0 ms on one CPU core; the same values)."""
    return t.index_select(0, idx.to(t.device))


class TorchClassifier(ClassifierMixin, BaseEstimator):
    """Base of the torch classifiers; subclasses add architecture arguments and
    :meth:`_build_module`. See the module docstring for the input convention.

    Parameters
    ----------
    n_aux : int
        Trailing scalar channels of a 3-D input.
    max_epochs : int
        Epoch budget (cosine learning-rate decay over it).
    batch_size : int
    lr : float
        Peak AdamW learning rate.
    weight_decay : float
        AdamW weight decay.
    label_smoothing : float
    val_fraction : float
        Fraction of the training *groups* (or windows, without groups) held out for early
        stopping; 0 trains the fixed budget. The split is carved from the data passed to
        ``fit`` only, i.e. from the source gears in the transfer study.
    patience : int
        Epochs without a better validation loss before stopping.
    aug_gain, aug_offset : float
        Std of a random per-window, per-channel gain factor (1 + N(0, aug_gain)) and offset
        (N(0, aug_offset)) applied to the signal channels while training [-]: robustness
        to the gauge gain and offset of an unseen gear left after normalisation.
    aug_crop : float
        Train on random crops of this fraction of the window (1: off); the global
        pooling makes the net length-agnostic, prediction uses the whole window.
    device : str
        "auto" (CUDA if present), "cpu", "cuda", "cuda:N"
        (:data:`learn.learners.devices.DEVICE_CHOICES`).
    precision : {"float32", "bfloat16", "auto"}
        Arithmetic of the forward passes: float32, or mixed precision (``torch.autocast``:
        matrix products and convolutions in bfloat16; parameters, optimiser state, batch
        norm, losses and outputs in float32); "auto": bfloat16 where the device has fast
        kernels for it (:func:`learn.learners.devices.resolve_precision`), so results
        differ in the last digits between machines. bfloat16 about halves the CNN's time
        on an AVX-512 CPU (``docs/results/transfer.md``); elsewhere it is emulated and
        slower.
    random_state : int, numpy Generator or None
    verbose : bool
        Log the loss per epoch.

    Attributes
    ----------
    classes_ : ndarray, shape (n_classes,)
    n_features_in_ : int
        Features of a 2-D input, channels (signals + scalars) of a 3-D input.
    input_shape_ : tuple of int
        Shape of one training window, (F,) or (C, T); later inputs must have as many
        dimensions, and the length T where the net needs it (MLP, ``pool="flatten"``).
    precision_ : str
        The arithmetic in use, "float32" or "bfloat16"
        (:func:`learn.learners.devices.resolve_precision`).
    module_ : torch.nn.Module
    history_ : list of dict
        Loss per epoch (and validation loss and accuracy with ``val_fraction`` > 0).
    """

    # ---------------------------------------------------------------- to override
    def _build_module(self, x_shape: tuple[int, ...], n_classes: int) -> nn.Module:
        raise NotImplementedError

    def _fixed_length(self) -> bool:
        """Whether the net needs the training length T of a 3-D input."""
        return False

    # ---------------------------------------------------------------- helpers
    def _store(self, args: dict) -> None:
        """Keep the ``__init__`` arguments (its ``locals()``) as attributes, unchanged."""
        for name, value in args.items():
            if name != "self":
                setattr(self, name, value)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.three_d_array = True  # (n, C, T) signals
        return tags

    def _check_X(self, X) -> np.ndarray:
        """Input of a fitted model as float32 after scikit-learn's checks (finite, n > 0,
        ``n_features_in_``) and the net's (dimensions and, where needed, length of fit)."""
        check_is_fitted(self, "module_")
        X = validate_data(self, X, reset=False, dtype=np.float32, allow_nd=True)
        if X.ndim != len(self.input_shape_) + 1:
            raise ValueError(f"X must have {len(self.input_shape_) + 1} dimensions as in fit, "
                             f"got shape {X.shape}")
        if X.ndim == 3 and self._fixed_length() and X.shape[2] != self.input_shape_[1]:
            raise ValueError(f"X has {X.shape[2]} time samples, but {type(self).__name__} "
                             f"needs the {self.input_shape_[1]} of fit")
        return X

    def prepare(self, X) -> torch.Tensor:
        """Windows checked and standardised with the statistics of ``fit``.

        Parameters
        ----------
        X : array, shape (n, C, T) or (n, F), or torch.Tensor
            A tensor is taken as prepared already and returned as it is.

        Returns
        -------
        torch.Tensor, float32, shape of ``X``
            What every method taking ``X`` accepts in its place; a fine-tuned or AdaBN
            copy keeps the statistics and reuses it (the transfer study prepares a job's
            evaluation and replay windows once for every k and adaptation).
        """
        return X if isinstance(X, torch.Tensor) else self._scale(self._check_X(X))

    def _scale(self, X: np.ndarray) -> torch.Tensor:
        X = np.asarray(X, dtype=np.float32)
        shape = (1, -1, 1) if X.ndim == 3 else (1, -1)
        X = (X - self.mean_.reshape(shape)) / self.scale_.reshape(shape)
        return torch.from_numpy(np.ascontiguousarray(X, dtype=np.float32))

    def _augment(self, xb: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
        if xb.ndim != 3:
            return xb
        c = xb.shape[1] - self.n_aux
        if self.aug_gain > 0 or self.aug_offset > 0:
            xb = xb.clone()
            shape = (xb.shape[0], c, 1)
            if self.aug_gain > 0:
                g = 1.0 + self.aug_gain * torch.randn(shape, generator=gen)
                xb[:, :c] *= g.to(xb.device)
            if self.aug_offset > 0:
                o = self.aug_offset * torch.randn(shape, generator=gen)
                xb[:, :c] += o.to(xb.device)
        if self.aug_crop < 1.0:
            t = xb.shape[2]
            n = max(8, int(round(self.aug_crop * t)))
            start = int(torch.randint(0, t - n + 1, (1,), generator=gen))
            xb = xb[:, :, start:start + n]
        return xb

    def check_params(self) -> None:
        """Refuse settings that ``fit`` would refuse, before any work.

        Raises
        ------
        ValueError
            For an unknown ``precision`` or ``device``
            (:data:`learn.learners.devices.DEVICE_CHOICES`).
        """
        resolve_precision(self.precision, torch.device("cpu"))
        check_device(self.device, "device")

    def _autocast(self):
        """The context of a forward pass at :attr:`precision` (class docstring)."""
        if self.precision_ == "float32":
            return contextlib.nullcontext()
        return torch.autocast(self.device_.type, dtype=torch.bfloat16)

    def _encode(self, y) -> np.ndarray:
        y = np.asarray(y)
        lookup = {c: i for i, c in enumerate(self.classes_)}
        try:
            return np.array([lookup[v] for v in y], dtype=np.int64)
        except KeyError as e:
            raise ValueError(f"label {e.args[0]!r} not among the classes seen in fit") from e

    def _val_split(self, n: int, groups, rng: np.random.Generator):
        if self.val_fraction <= 0:
            return np.arange(n), np.array([], dtype=int)
        if groups is None:
            groups = np.arange(n)
        groups = np.asarray(groups)
        uniq = np.unique(groups)
        n_val = max(1, int(round(self.val_fraction * uniq.size)))
        val_groups = rng.choice(uniq, size=n_val, replace=False)
        is_val = np.isin(groups, val_groups)
        return np.flatnonzero(~is_val), np.flatnonzero(is_val)

    def _run_epochs(self, X: torch.Tensor, yi: np.ndarray, params, lr: float, n_steps_epoch,
                    n_epochs: int, gen: torch.Generator, X_val: torch.Tensor,
                    y_val: np.ndarray) -> list[dict]:
        """Train ``params`` for ``n_epochs`` with AdamW + cosine decay; early stopping on
        (X_val, y_val) unless empty. Returns the history; restores the best state."""
        module = self.module_
        opt, sched, loss_fn = self._optimiser(params, lr, max(1, n_epochs * n_steps_epoch))
        yt = torch.from_numpy(yi).to(X.device)
        n = X.shape[0]
        bs = min(self.batch_size, n)
        history, best, best_state, bad = [], math.inf, None, 0
        for epoch in range(n_epochs):
            module.train()
            perm = torch.randperm(n, generator=gen)
            # summed where the losses are, read once an epoch: no wait on a GPU per step
            tot, seen = torch.zeros((), dtype=torch.float64, device=X.device), 0
            for s in range(n_steps_epoch):
                idx = perm[s * bs:(s + 1) * bs]
                if idx.numel() < 2:  # batch norm needs two windows
                    continue
                loss = self._step(rows(X, idx), rows(yt, idx), gen, opt, sched, loss_fn)
                tot += loss.detach().double() * idx.numel()
                seen += idx.numel()
            rec = {"epoch": epoch, "loss": float(tot) / max(seen, 1)}
            if len(X_val):
                logits, yv = self._logits(X_val), torch.from_numpy(y_val)
                vl = float(loss_fn(logits, yv))
                va = float((logits.argmax(1) == yv).float().mean())
                rec.update(val_loss=vl, val_accuracy=va)
                if vl < best - 1e-4:
                    best, bad = vl, 0
                    best_state = copy.deepcopy(module.state_dict())
                else:
                    bad += 1
            history.append(rec)
            if self.verbose:
                log.info("epoch %d %s", epoch, rec)
            if len(X_val) and bad >= self.patience:
                break
        if best_state is not None:
            module.load_state_dict(best_state)
        module.eval()
        return history

    def _optimiser(self, params, lr: float, total: int):
        """AdamW (all parameters at once, ``foreach``: the same numbers, faster on a CPU) at
        peak ``lr`` with cosine decay over ``total`` steps, and the loss."""
        opt = torch.optim.AdamW(params, lr=lr, weight_decay=self.weight_decay, foreach=True)
        sched = torch.optim.lr_scheduler.LambdaLR(
            opt, lambda s: 0.5 * (1 + math.cos(math.pi * min(s, total) / total)))
        return opt, sched, nn.CrossEntropyLoss(label_smoothing=self.label_smoothing)

    def _step(self, xb: torch.Tensor, yb: torch.Tensor, gen: torch.Generator, opt, sched,
              loss_fn) -> torch.Tensor:
        """One optimiser step on the augmented batch (xb, yb); returns its loss."""
        xb = self._augment(xb, gen).to(self.device_)
        opt.zero_grad(set_to_none=True)
        with self._autocast():
            loss = loss_fn(self.module_(xb).float(), yb.to(self.device_))
        loss.backward()
        opt.step()
        sched.step()
        return loss

    @torch.no_grad()
    def _logits(self, X: torch.Tensor, batch: int = 512, embed: bool = False) -> torch.Tensor:
        """The net's outputs (or penultimate features), batch by batch, on the CPU."""
        self.module_.eval()
        net = self.module_.embed if embed else self.module_
        with self._autocast():
            out = [net(X[i:i + batch].to(self.device_)).float().cpu()
                   for i in range(0, X.shape[0], batch)]
        return torch.cat(out)

    # ---------------------------------------------------------------- public API
    def fit(self, X, y, groups=None):
        """Train from scratch.

        Parameters
        ----------
        X : array, shape (n, C, T) or (n, F)
        y : array of labels, shape (n,)
        groups : array, shape (n,), optional
            Group of each window (e.g. class and variant); the early-stopping validation
            split keeps whole groups apart. Ignored when ``val_fraction`` is 0.

        Returns
        -------
        self

        Raises
        ------
        ValueError
            On non-finite or empty ``X``, ``X`` not 2-D or 3-D, ``len(y) != n`` or
            continuous ``y``, an unknown ``precision`` or ``device``, or a CUDA device
            on a machine without one.
        """
        Xt, yi = self._begin_fit(X, y)
        seed = _seed_of(self.random_state)
        tr, va = self._val_split(len(yi), groups, np.random.default_rng(seed))
        gen = torch.Generator().manual_seed(seed)
        steps = max(1, math.ceil(len(tr) / self.batch_size))
        with _local_seed(seed, self.device_):  # weights and dropout; global RNG untouched
            self.module_ = self._new_module(len(yi))
            self.history_ = self._run_epochs(
                Xt[tr], yi[tr], list(self.module_.parameters()), self.lr, steps,
                self.max_epochs, gen, Xt[va], yi[va])
        return self

    def _begin_fit(self, X, y) -> tuple[torch.Tensor, np.ndarray]:
        """The checks, classes, device, arithmetic and standardisation of ``fit``; returns
        the standardised windows on the device and the class indices."""
        self.check_params()
        X, y = validate_data(self, X, y, dtype=np.float32, allow_nd=True)
        if X.ndim not in (2, 3):
            raise ValueError(f"X must be (n, C, T) or (n, F); got shape {X.shape}")
        check_classification_targets(y)
        self.classes_ = np.unique(y)
        self.input_shape_ = X.shape[1:]
        self.device_ = resolve_device(self.device, "device")
        self.precision_ = resolve_precision(self.precision, self.device_)
        axes = (0, 2) if X.ndim == 3 else (0,)
        self.mean_ = X.mean(axis=axes)
        sd = X.std(axis=axes)
        self.scale_ = np.where(sd > 1e-8, sd, 1.0).astype(np.float32)
        return self._scale(X).to(self.device_), self._encode(y)

    def _new_module(self, n: int) -> nn.Module:
        """A freshly initialised net for ``n`` windows of ``input_shape_``, on the device
        (its weights drawn from torch's default generator)."""
        shape = (n, *self.input_shape_)
        return self._build_module(shape, len(self.classes_)).to(self.device_)

    def fine_tune(self, X, y, mode: str = "all", steps: int = 100, lr: float | None = None,
                  X_replay=None, y_replay=None, replay: float = 1.0, random_state=None):
        """Continue training on a few labelled windows of a new domain (in place).

        Batch-norm statistics stay those of the source (BN layers in eval mode), and the
        input standardisation of ``fit`` is kept: a handful of windows cannot re-estimate
        them. Optionally each batch of target windows is joined by ``replay`` times as many
        random source windows (``X_replay``), which keeps a 6-window fine-tuning from
        forgetting what the source taught.

        Parameters
        ----------
        X, y : arrays
            The labelled target windows (k per class); labels among ``classes_``.
        mode : {"all", "last"}
            Update every weight, or the final linear layer only.
        steps : int
            Optimiser steps (a fixed budget: with k windows per class no validation
            split exists, and none may come from the target's evaluation windows).
        lr : float, optional
            Peak learning rate (cosine decay); default ``self.lr / 10`` for "all",
            ``self.lr`` for "last".
        X_replay, y_replay : arrays, optional
            Labelled source windows to mix into every batch.
        replay : float
            Source windows per target window in a batch (0: none).
        random_state : int, optional
            Seed of batches and augmentation; default derived from ``random_state``.

        Returns
        -------
        self

        Raises
        ------
        ValueError
            On an unknown mode, an unseen label or an input unlike that of ``fit``.
        sklearn.exceptions.NotFittedError
            On an unfitted model (a ``ValueError``).
        """
        if mode not in ("all", "last"):
            raise ValueError(f"mode must be 'all' or 'last', got {mode!r}")
        check_is_fitted(self, "module_")
        if len(X) == 0 or steps <= 0:
            return self
        dev = self.device_
        yt = torch.from_numpy(self._encode(y)).to(dev)
        Xt = self.prepare(X).to(dev)
        use_replay = X_replay is not None and replay > 0 and len(X_replay) > 0
        if use_replay:
            Xr = self.prepare(X_replay).to(dev)
            yr = torch.from_numpy(self._encode(y_replay)).to(dev)
        module = self.module_
        params = list(module.head.parameters()) if mode == "last" else list(module.parameters())
        if lr is None:
            lr = self.lr if mode == "last" else self.lr / 10
        trainable = {id(p) for p in params}
        saved = {id(p): p.requires_grad for p in module.parameters()}
        for p in module.parameters():
            p.requires_grad_(id(p) in trainable)
        seed = _seed_of(self.random_state if random_state is None else random_state) + 1
        gen = torch.Generator().manual_seed(seed)
        opt, sched, loss_fn = self._optimiser(params, lr, steps)
        n = len(X)
        bs = min(self.batch_size, n)
        history = []
        try:
            with _local_seed(seed, self.device_):
                module.train()
                for m in module.modules():
                    if isinstance(m, nn.BatchNorm1d):
                        m.eval()
                perm, pos = torch.randperm(n, generator=gen), 0
                for _ in range(steps):
                    if pos + bs > n:
                        perm, pos = torch.randperm(n, generator=gen), 0
                    idx = perm[pos:pos + bs]
                    pos += bs
                    xb, yb = rows(Xt, idx), rows(yt, idx)
                    if use_replay:
                        ridx = torch.randint(0, len(Xr), (max(1, int(round(replay * bs))),),
                                             generator=gen)
                        xb, yb = torch.cat([xb, rows(Xr, ridx)]), torch.cat([yb, rows(yr, ridx)])
                    loss = self._step(xb, yb, gen, opt, sched, loss_fn)
                    history.append(loss.detach())  # read after the steps: no wait per step
        finally:
            for p in module.parameters():
                p.requires_grad_(saved[id(p)])
            module.eval()
        self.finetune_history_ = [float(v) for v in history]
        return self

    @torch.no_grad()
    def adapt_bn(self, X, batch: int = 256):
        """AdaBN (Li et al. 2018): re-estimate every batch-norm mean and variance on
        unlabelled windows of the new domain (in place); weights are unchanged.

        Parameters
        ----------
        X : array, (n, C, T) or (n, F)
            Unlabelled target windows (labels are never needed).

        Returns
        -------
        self
        """
        Xt = self.prepare(X)
        bns = [m for m in self.module_.modules() if isinstance(m, nn.BatchNorm1d)]
        if not bns:
            return self
        saved = [m.momentum for m in bns]
        for m in bns:
            m.reset_running_stats()
            m.momentum = None  # cumulative average over the batches
        self.module_.eval()  # dropout off: only the batch-norm statistics are re-estimated
        for m in bns:
            m.train()
        for i in range(0, Xt.shape[0], batch):
            with self._autocast():
                self.module_(Xt[i:i + batch].to(self.device_))
        for m, mom in zip(bns, saved, strict=True):
            m.momentum = mom
        self.module_.eval()
        return self

    def predict_proba(self, X) -> np.ndarray:
        """Class probabilities, shape (n, n_classes), columns in ``classes_`` order."""
        return torch.softmax(self._logits(self.prepare(X)), dim=1).numpy()

    def decision_function(self, X) -> np.ndarray:
        """Logits, shape (n, n_classes); with two classes scikit-learn's binary form, the
        logit of ``classes_[1]`` minus that of ``classes_[0]``, shape (n,) (> 0: class 1)."""
        logits = self._logits(self.prepare(X)).numpy()
        return logits[:, 1] - logits[:, 0] if logits.shape[1] == 2 else logits

    def predict(self, X) -> np.ndarray:
        """Predicted labels, shape (n,): the class of the largest logit."""
        logits = self._logits(self.prepare(X)).numpy()
        return self.classes_[logits.argmax(axis=1)]

    def embed(self, X, batch: int = 512) -> np.ndarray:
        """Penultimate-layer features, shape (n, width of the head's input)."""
        return self._logits(self.prepare(X), batch, embed=True).numpy()


class MLPClassifierTorch(TorchClassifier):
    """Multi-layer perceptron (paper Table VI has 3 x 10 ReLU units; default here wider,
    with batch norm and dropout). Flattens a signal input; see :class:`TorchClassifier`.

    Parameters
    ----------
    hidden : tuple of int
        Widths of the hidden layers.
    dropout : float
    """

    def __init__(self, hidden=(128, 64), dropout=0.1, *, n_aux=0, max_epochs=60,
                 batch_size=64, lr=3e-3, weight_decay=1e-2, label_smoothing=0.0,
                 val_fraction=0.0, patience=8, aug_gain=0.0, aug_offset=0.0, aug_crop=1.0,
                 device="auto", precision="float32", random_state=None, verbose=False):
        self._store(locals())

    def _build_module(self, x_shape, n_classes):
        if len(x_shape) == 3:
            n_in = (x_shape[1] - self.n_aux) * x_shape[2] + self.n_aux
        else:
            n_in = x_shape[1]
        return MLPNet(n_in, self.n_aux if len(x_shape) == 3 else 0, n_classes,
                      tuple(self.hidden), self.dropout)

    def _fixed_length(self) -> bool:  # the flattened signal fixes T
        return True

    def _augment(self, xb, gen):  # crops would change the flattened length
        if self.aug_crop < 1.0:
            raise ValueError("aug_crop < 1 is not possible for an MLP (fixed input length)")
        return super()._augment(xb, gen)


class CNN1DClassifier(TorchClassifier):
    """1D convolutional net over the signal channels with global average pooling; the
    auxiliary scalars join after pooling. See :class:`TorchClassifier`.

    Parameters
    ----------
    channels, kernel_sizes, strides : tuple of int
        One entry per conv block (conv -> batch norm -> ReLU); early strides keep the
        CPU cost low (~4000 windows x 5 x 1200 samples: about a minute per ten epochs on
        two cores).
    head_hidden : int
        Width of the hidden layer of the head.
    dropout : float
    padding_mode : {"zeros", "circular"}
        "circular" for periodic inputs (the angle-domain residuals of one revolution).
    pool : {"avg", "flatten"}
        "avg": global average pooling, invariant to shifts in time (signals); "flatten":
        keeps the position along the input (spectra and feature vectors such as
        Selection 3, whose index is an order or a feature).
    """

    def __init__(self, channels=(16, 32, 64, 64), kernel_sizes=(9, 7, 7, 5),
                 strides=(4, 2, 2, 2), head_hidden=64, dropout=0.1, padding_mode="zeros",
                 pool="avg", *, n_aux=0, max_epochs=30, batch_size=64, lr=3e-3,
                 weight_decay=1e-2, label_smoothing=0.0, val_fraction=0.0, patience=8,
                 aug_gain=0.0, aug_offset=0.0, aug_crop=1.0, device="auto",
                 precision="float32", random_state=None, verbose=False):
        self._store(locals())

    def _build_module(self, x_shape, n_classes):
        n_ch = x_shape[1] if len(x_shape) == 3 else 1
        return CNN1DNet(n_ch, self.n_aux if len(x_shape) == 3 else 0, n_classes,
                        tuple(self.channels), tuple(self.kernel_sizes), tuple(self.strides),
                        self.head_hidden, self.dropout, self.padding_mode, self.pool,
                        x_shape[-1])

    def _fixed_length(self) -> bool:  # avg pooling is length-agnostic, flattening is not
        return self.pool == "flatten"

    def _augment(self, xb, gen):
        if self.aug_crop < 1.0 and self.pool == "flatten":
            raise ValueError("aug_crop < 1 is not possible with pool='flatten' (fixed input "
                             "length)")
        return super()._augment(xb, gen)

