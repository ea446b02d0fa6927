"""The torch modules behind the classifiers of :mod:`learn.learners.nets`: a fully
connected net over features or flattened signals (:class:`MLPNet`) and a 1D-CNN of
strided convolution blocks with global pooling (:class:`CNN1DNet`).

Both read the input convention of :mod:`learn.learners.nets`: (B, C, T) signals whose
last ``n_aux`` channels are per-window scalars held constant along time (read at t = 0),
or (B, F) features. The estimators own training, devices and precision; a module is
only its layers and its forward pass.
"""

from __future__ import annotations

import torch
from torch import nn


class MLPNet(nn.Module):
    """Fully connected net: (B, F) or (B, C, T) -> logits (B, K).

    A 3-D input is flattened over its signal channels; its ``n_aux`` trailing scalar
    channels are read at t = 0 and concatenated, so they are not repeated T times.
    """

    def __init__(self, n_in: int, n_aux: int, n_classes: int, hidden: tuple[int, ...],
                 dropout: float):
        super().__init__()
        self.n_aux = n_aux
        layers: list[nn.Module] = []
        width = n_in
        for h in hidden:
            layers += [nn.Linear(width, h), nn.BatchNorm1d(h), nn.ReLU(), nn.Dropout(dropout)]
            width = h
        self.body = nn.Sequential(*layers)
        self.head = nn.Linear(width, n_classes)

    def embed(self, x: torch.Tensor) -> torch.Tensor:
        if x.ndim == 3:
            c = x.shape[1] - self.n_aux
            sig = x[:, :c].flatten(1)  # (B, c*T)
            x = torch.cat([sig, x[:, c:, 0]], dim=1) if self.n_aux else sig
        return self.body(x)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.embed(x))


class CNN1DNet(nn.Module):
    """1D-CNN: strided conv blocks, pooling, scalars joined, MLP head.

    (B, C, T) -> conv blocks -> (B, ch[-1], T') -> pool -> (B, P)
    -> concat aux scalars (B, n_aux) -> Linear-ReLU -> Linear -> logits (B, K).
    ``pool="avg"``: mean over T' (P = ch[-1]), invariant to shifts in time, for signals;
    ``pool="flatten"``: (B, ch[-1] * T') keeps the position, for inputs whose index has a
    meaning (spectra, feature vectors; needs ``length`` = T).
    A 2-D input (B, F) is read as one channel of length F.
    """

    def __init__(self, n_channels: int, n_aux: int, n_classes: int,
                 channels: tuple[int, ...], kernel_sizes: tuple[int, ...],
                 strides: tuple[int, ...], head_hidden: int, dropout: float,
                 padding_mode: str = "zeros", pool: str = "avg", length: int | None = None):
        super().__init__()
        if not len(channels) == len(kernel_sizes) == len(strides):
            raise ValueError("channels, kernel_sizes and strides must have the same length")
        if pool not in ("avg", "flatten"):
            raise ValueError(f"pool must be 'avg' or 'flatten', got {pool!r}")
        if pool == "flatten" and not (length and length > 0):
            raise ValueError("pool='flatten' needs the input length (length > 0)")
        self.n_aux = n_aux
        self.pool = pool
        blocks: list[nn.Module] = []
        c_in = n_channels - n_aux
        for c_out, k, s in zip(channels, kernel_sizes, strides, strict=True):
            blocks += [nn.Conv1d(c_in, c_out, k, stride=s, padding=k // 2, bias=False,
                                 padding_mode=padding_mode),
                       nn.BatchNorm1d(c_out), nn.ReLU()]
            c_in = c_out
        self.features = nn.Sequential(*blocks)
        n_pooled = c_in
        if pool == "flatten":
            n_t = length
            for k, s in zip(kernel_sizes, strides, strict=True):
                n_t = (n_t + 2 * (k // 2) - k) // s + 1
            n_pooled = c_in * n_t
        self.body = nn.Sequential(nn.Linear(n_pooled + n_aux, head_hidden), nn.ReLU(),
                                  nn.Dropout(dropout))
        self.head = nn.Linear(head_hidden, n_classes)

    def embed(self, x: torch.Tensor) -> torch.Tensor:
        if x.ndim == 2:
            x = x[:, None, :]  # (B, 1, F)
        c = x.shape[1] - self.n_aux
        z = self.features(x[:, :c])  # (B, ch[-1], T')
        z = z.mean(dim=2) if self.pool == "avg" else z.flatten(1)  # (B, P)
        if self.n_aux:
            z = torch.cat([z, x[:, c:, 0]], dim=1)  # (B, ch[-1] + n_aux)
        return self.body(z)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.embed(x))


__all__ = ["CNN1DNet", "MLPNet"]
