"""Several seeds of one torch net trained at once: :func:`fit_seeds`.

The copies' parameters are stacked and each step is one vectorised forward and backward
pass of all of them (``torch.func``), which fills a GPU that one small net leaves idle
(``docs/results/speed.md``, "Nets on a GPU"). Each copy is a plain fitted
:class:`learn.learners.nets.TorchClassifier` afterwards.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import torch
from sklearn.base import clone
from torch import nn

from .nets import TorchClassifier, _local_seed, _seed_of, rows


def fit_seeds(estimator: TorchClassifier, X, y, seeds, groups=None, *,
              compile: bool = False) -> list[TorchClassifier]:
    """One copy of a torch classifier per seed, trained at once on a device.

    The copies' parameters are stacked and every step is one vectorised forward and
    backward pass of all of them (``torch.func.vmap`` over ``torch.func.functional_call``,
    https://pytorch.org/tutorials/intermediate/ensembling.html) and one AdamW step (its
    arithmetic is elementwise, so a stacked step is each copy's own). A copy gets what
    ``clone(estimator).set_params(random_state=seed).fit(X, y, groups)`` gives it: the same
    initial weights, validation split, batches, augmentation and early stopping; only
    the dropout masks are drawn otherwise (one generator for all copies) and sums run in
    another order, so the weights agree with one-by-one training to rounding where
    ``dropout`` is 0 (``tests/learn/test_deep_nets.py``), and in distribution otherwise.
    On a GPU this replaces the copies' many small kernels by a few larger ones
    (``scripts/bench_nets.py`` prints time per model and accuracy both ways).

    Parameters
    ----------
    estimator : TorchClassifier
        The settings (unchanged; copies are made with :func:`sklearn.base.clone`).
    X : array, shape (n, C, T) or (n, F)
    y : array of labels, shape (n,)
    seeds : sequence of int
        ``random_state`` of each copy.
    groups : array, shape (n,), optional
        As in :meth:`TorchClassifier.fit`. Where the copies' validation splits leave
        training sets of unequal size (whole groups of unequal size), their batches do
        not stack and the copies are trained one after the other.
    compile : bool
        Compile the stacked forward pass (``torch.compile``). Batches keep their shape
        from epoch to epoch (the full one and the last, smaller one), so it is compiled
        a few times per fit and then reused; whether that pays depends on the device and
        the net (``scripts/bench_nets.py``, mode ``compiled``).

    Returns
    -------
    list of TorchClassifier
        Fitted copies, in the order of ``seeds``; each one a plain fitted classifier.

    Raises
    ------
    ValueError
        No seed, or what :meth:`TorchClassifier.fit` refuses.
    """
    nets = [clone(estimator).set_params(random_state=int(s)) for s in seeds]
    if not nets:
        raise ValueError("seeds: give at least one seed")
    first = nets[0]
    Xt, yi = first._begin_fit(X, y)
    plans = []
    for net in nets:
        for name in ("n_features_in_", "classes_", "input_shape_", "device_", "precision_",
                     "mean_", "scale_"):
            setattr(net, name, getattr(first, name))
        seed = _seed_of(net.random_state)
        tr, va = net._val_split(len(yi), groups, np.random.default_rng(seed))
        with _local_seed(seed, first.device_):
            net.module_ = net._new_module(len(yi))
        plans.append((tr, va, torch.Generator().manual_seed(seed)))
    if len({(len(tr), len(va)) for tr, va, _ in plans}) > 1:
        return [net.fit(X, y, groups) for net in nets]
    with _local_seed(_seed_of(first.random_state), first.device_):  # dropout masks
        _StackedRun(nets, Xt, yi, plans, compile).train()
    return nets


class _FloatBatchNorm1d(nn.BatchNorm1d):
    """Batch norm of a float32 input: in bfloat16, torch's vmap of batch norm's backward
    on CUDA refuses bfloat16 inputs beside float32 statistics (torch 2.11), so the stacked
    copies normalise in float32 (their convolutions and products stay in bfloat16)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return super().forward(x.float())


class _StackedRun:
    """The training loop of :func:`fit_seeds`: :meth:`TorchClassifier._run_epochs` for
    stacked copies, each with its own batches, augmentation and early stopping."""

    def __init__(self, nets: list[TorchClassifier], Xt: torch.Tensor, yi: np.ndarray,
                 plans: list[tuple[np.ndarray, np.ndarray, torch.Generator]],
                 compile: bool = False):
        first = nets[0]
        self.nets, self.Xt, self.plans, self.first = nets, Xt, plans, first
        self.yt = torch.from_numpy(yi).to(Xt.device)
        self.params, self.buffers = torch.func.stack_module_state([n.module_ for n in nets])
        self.base = copy.deepcopy(first.module_).to("meta")
        for m in self.base.modules():  # the template only: the copies' own nets unchanged
            if isinstance(m, nn.BatchNorm1d):
                m.__class__ = _FloatBatchNorm1d
        self.forward = torch.func.vmap(self._one, randomness="different")
        if compile:
            self.forward = torch.compile(self.forward)

    def _one(self, params, buffers, x):
        return torch.func.functional_call(self.base, (params, buffers), (x,))

    def _logits_and_losses(self, xb: torch.Tensor, yb: torch.Tensor
                           ) -> tuple[torch.Tensor, torch.Tensor]:
        """Each copy's logits on its batch, (K, B, classes), and the cross-entropy of each
        window, (K, B)."""
        with self.first._autocast():
            logits = self.forward(self.params, self.buffers, xb).float()
        return logits, nn.functional.cross_entropy(
            logits.transpose(1, 2), yb, reduction="none",
            label_smoothing=self.first.label_smoothing)

    def _epoch(self, opt, sched, steps: int, bs: int) -> torch.Tensor:
        """One epoch of every copy; returns the mean training loss of each, shape (K,)."""
        self.base.train()
        perms = [torch.from_numpy(tr)[torch.randperm(len(tr), generator=gen)]
                 for tr, _, gen in self.plans]
        tot, seen = torch.zeros(len(self.nets), dtype=torch.float64, device=self.Xt.device), 0
        for s in range(steps):
            idx = [p[s * bs:(s + 1) * bs] for p in perms]
            if idx[0].numel() < 2:  # batch norm needs two windows
                continue
            xb = torch.stack([net._augment(rows(self.Xt, i), gen) for net, i, (_, _, gen)
                              in zip(self.nets, idx, self.plans, strict=True)])
            yb = torch.stack([rows(self.yt, i) for i in idx])
            opt.zero_grad(set_to_none=True)
            losses = self._logits_and_losses(xb.to(self.Xt.device), yb)[1].mean(1)
            losses.sum().backward()  # the copies' parameters are apart: each its own gradient
            opt.step()
            sched.step()
            tot += losses.detach().double() * idx[0].numel()
            seen += idx[0].numel()
        return tot / max(seen, 1)

    @torch.no_grad()
    def _validate(self, batch: int = 512) -> tuple[np.ndarray, np.ndarray]:
        """Validation loss and accuracy of each copy on its own held-out windows."""
        self.base.eval()
        vas = [torch.from_numpy(va) for _, va, _ in self.plans]
        loss, hits = 0.0, 0.0
        for i in range(0, len(vas[0]), batch):
            idx = [v[i:i + batch] for v in vas]
            xb = torch.stack([rows(self.Xt, j) for j in idx])
            yb = torch.stack([rows(self.yt, j) for j in idx])
            logits, each = self._logits_and_losses(xb, yb)
            loss = loss + each.sum(1)
            hits = hits + (logits.argmax(2) == yb).sum(1)
        n = len(vas[0])
        return (loss / n).cpu().numpy(), (hits / n).cpu().numpy()

    def _state(self, k: int) -> dict[str, torch.Tensor]:
        return {name: t[k].detach().clone()
                for name, t in (*self.params.items(), *self.buffers.items())}

    def train(self) -> None:
        """Train every copy; each keeps its best state (early stopping) and history."""
        first, k_all = self.first, range(len(self.nets))
        n_tr = len(self.plans[0][0])
        bs, steps = min(first.batch_size, n_tr), max(1, math.ceil(n_tr / first.batch_size))
        opt, sched, _ = first._optimiser(list(self.params.values()), first.lr,
                                         max(1, first.max_epochs * steps))
        has_val = len(self.plans[0][1]) > 0
        history = [[] for _ in k_all]
        best, best_state, bad = [math.inf for _ in k_all], [None for _ in k_all], [0 for _ in k_all]
        active = [True for _ in k_all]
        for epoch in range(first.max_epochs):
            train_loss = self._epoch(opt, sched, steps, bs).cpu().numpy()
            val_loss, val_acc = self._validate() if has_val else (None, None)
            for k in (k for k in k_all if active[k]):
                rec = {"epoch": epoch, "loss": float(train_loss[k])}
                if has_val:
                    rec.update(val_loss=float(val_loss[k]), val_accuracy=float(val_acc[k]))
                    if val_loss[k] < best[k] - 1e-4:
                        best[k], bad[k], best_state[k] = float(val_loss[k]), 0, self._state(k)
                    else:
                        bad[k] += 1
                    active[k] = bad[k] < first.patience
                history[k].append(rec)
            if has_val and not any(active):
                break
        for k, net in enumerate(self.nets):
            net.module_.load_state_dict(best_state[k] or self._state(k))
            net.module_.eval()
            net.history_ = history[k]
