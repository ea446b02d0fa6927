"""How a window is recorded: its start, and the amplifier that samples the bridges.

The data-set option ``acquisition`` (:class:`Acquisition`; presets ``conf/dataset/paper.yaml``
and ``bench.yaml``): ``start: fixed`` simulates every window from the same initial state,
as the paper (Sec. III-B), ``start: random`` cuts windows at arbitrary times, as a bench
(:func:`start_angles`). ``amplifier`` (:class:`Amplifier`, :func:`acquire`) models a
delta-sigma bridge ADC: oversampled synthesis, sinc^order decimation, sampling, input
noise, quantisation and clipping, all in mV/V. The option's keys, the derivation and the
bench preset's source (TI ADS131M04, SBAS890 Table 7-1): docs/PHYSICS.md sec. 9.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

START_MODES = ("fixed", "random")


@dataclass
class Amplifier:
    """A delta-sigma bridge ADC channel, identical for the five bridges.

    Attributes
    ----------
    name : str
        Device name, for reports.
    noise_uv_rms : float
        Input-referred noise at the data rate [µV rms], >= 0.
    excitation_v : float
        Bridge excitation voltage [V], > 0 (converts V at the input to mV/V).
    vref_v : float
        ADC reference voltage [V], > 0.
    gain : float
        PGA gain [-], > 0; full scale ±vref_v / gain at the input.
    bits : int
        ADC resolution [bit], in [8, 32].
    order : int
        Order of the sinc decimation filter [-], in [1, 5] (3 for sinc3).
    oversample : int
        Fine samples per output sample used to model the filter and aliasing [-], in
        [1, 64].
    """

    name: str
    noise_uv_rms: float
    excitation_v: float
    vref_v: float
    gain: float
    bits: int = 24
    order: int = 3
    oversample: int = 4

    @property
    def noise_mvv(self) -> float:
        """Noise in bridge units [mV/V rms]."""
        return self.noise_uv_rms * 1e-3 / self.excitation_v

    @property
    def range_mvv(self) -> float:
        """Half of the input range in bridge units [mV/V]."""
        return self.vref_v / self.gain / self.excitation_v * 1e3

    @property
    def lsb_mvv(self) -> float:
        """Quantisation step [mV/V]."""
        return 2.0 * self.range_mvv / 2.0**self.bits

    def check(self, where: str) -> None:
        """Refuse a setting outside its range, in one line naming the key (run by
        :func:`swgsim.base.typed.check_tree`).

        Parameters
        ----------
        where : str
            Full name of the amplifier for messages, e.g. ``dataset.acquisition.amplifier``.

        Raises
        ------
        ValueError
            ``<where>.<field> must lie in [lo, hi], got ...`` (the ranges above; ``bits``,
            ``order`` and ``oversample`` whole numbers).
        """
        for k, (lo, hi, incl) in _AMP_RANGES.items():
            v = float(getattr(self, k))
            ok = (lo <= v if incl else lo < v) and v <= hi and np.isfinite(v)
            if k in ("bits", "order", "oversample"):
                ok = ok and v == int(v)
            if not ok:
                br = "[" if incl else "("
                raise ValueError(f"{where}.{k} must lie in {br}{lo}, {hi}], got "
                                 f"{getattr(self, k)}")

    def lead_samples(self, fs_hz: float) -> int:
        """Output samples simulated before and after a window so that the filter sees
        the signal's history [-] (the filter spans ``order`` output periods)."""
        return int(self.order) + 1

    def group_delay_s(self, fs_hz: float) -> float:
        """Delay of the sinc filter [s]: order · (oversample − 1) / 2 fine samples."""
        return self.order * (self.oversample - 1) / 2 / (self.oversample * fs_hz)


@dataclass
class Acquisition:
    """How a data set's windows are recorded (the data-set option ``acquisition``): how
    they start and how they are sampled; the defaults are the paper's acquisition.

    Attributes
    ----------
    start : {"fixed", "random"}
    wg_start_deg : float
        Input angle at the start of every simulation with ``start="fixed"`` [deg].
    amplifier : Amplifier or None
        None: ideal sampling (noise-free, no filter).
    """

    start: str = "fixed"
    wg_start_deg: float = 0.0
    amplifier: Amplifier | None = None

    def check(self, where: str) -> None:
        """Refuse a start mode or start angle outside its range, in one line naming the
        key (run by :func:`swgsim.base.typed.check_tree` when a data set is planned, after
        its amplifier's :meth:`Amplifier.check`).

        Parameters
        ----------
        where : str
            Full name of the option for messages, e.g. ``dataset.acquisition``.

        Raises
        ------
        ValueError
            ``start`` not one of :data:`START_MODES`; ``wg_start_deg`` not finite.
        """
        if self.start not in START_MODES:
            raise ValueError(f"{where}.start must be one of {list(START_MODES)}, "
                             f"got {self.start!r}")
        if not np.isfinite(float(self.wg_start_deg)):
            raise ValueError(f"{where}.wg_start_deg must be finite [deg], got "
                             f"{self.wg_start_deg}")


_AMP_RANGES = {  # key: (lower, upper, lower inclusive)
    "noise_uv_rms": (0.0, 1e4, True),
    "excitation_v": (0.0, 50.0, False),
    "vref_v": (0.0, 50.0, False),
    "gain": (0.0, 1e4, False),
    "bits": (8, 32, True),
    "order": (1, 5, True),
    "oversample": (1, 64, True),
}


def start_angles(acq: Acquisition, n: int, rng: np.random.Generator,
                 ratio: float) -> np.ndarray:
    """Input angle φ_in at the start of each window's simulation [rad], shape (n,).

    ``fixed``: ``wg_start_deg`` for every window. ``random``: uniform over [0, 2π N), so
    that the WG angle and the output angle are both uniform (docs/PHYSICS.md sec. 9). Draws from
    ``rng`` in both cases, so that other streams do not depend on the mode.
    """
    u = rng.uniform(0.0, 1.0, size=n)
    if acq.start == "fixed":
        return np.full(n, np.deg2rad(acq.wg_start_deg))
    return 2 * np.pi * float(ratio) * u


def sinc_taps(length: int, order: int) -> np.ndarray:
    """FIR taps of the sinc^order decimation filter at the fine rate, unit DC gain.

    ``order`` moving averages of ``length`` samples in cascade (a delta-sigma converter's
    sinc filter with ``length`` fine samples per output sample): response
    (sin(π f L / f_fine) / (L sin(π f / f_fine)))^order, zeros at multiples of the output
    rate f_fine / L.

    Returns
    -------
    ndarray, shape (order (length − 1) + 1,)
    """
    box = np.full(int(length), 1.0 / int(length))
    taps = np.ones(1)
    for _ in range(int(order)):
        taps = np.convolve(taps, box)
    return taps


def acquire(signals: np.ndarray, amp: Amplifier, rng: np.random.Generator,
            n_lead: int) -> np.ndarray:
    """Record fine-grid bridge signals with ``amp``: filter, sample, noise, quantise.

    :func:`sample` then :func:`digitise`; same parameters, plus ``rng`` (noise stream).
    """
    return digitise(sample(signals, amp, n_lead), amp, rng)


def sample(signals: np.ndarray, amp: Amplifier, n_lead: int) -> np.ndarray:
    """Filter and sample fine-grid bridge signals with ``amp`` (no noise, no quantisation).

    Parameters
    ----------
    signals : ndarray, shape (n_windows, n_sensors, oversample · (n_t + 2 n_lead))
        Bridge outputs on the fine grid [mV/V], starting ``n_lead`` output periods before
        the window and ending ``n_lead`` after it.
    amp : Amplifier
    n_lead : int
        Lead (and tail) output samples, >= ``amp.order`` (filter history).

    Returns
    -------
    ndarray, shape (n_windows, n_sensors, n_t)
        Sampled windows [mV/V]: the sinc output at the end of each output period
        (:func:`sinc_taps`), so a window lags the fine signal by
        :meth:`Amplifier.group_delay_s` (a pure delay; windows start at arbitrary times
        anyway).

    Raises
    ------
    ValueError
        If the length is not a multiple of ``oversample`` or ``n_lead`` is too short.
    """
    q = int(amp.oversample)
    n_fine = signals.shape[-1]
    if n_fine % q or n_fine // q <= 2 * n_lead:
        raise ValueError(f"signals of {n_fine} fine samples do not hold oversample={q} x "
                         f"(n_t + 2 x {n_lead})")
    if n_lead < amp.order:
        raise ValueError(f"n_lead must be >= the filter order {amp.order}, got {n_lead}")
    n_t = n_fine // q - 2 * n_lead
    taps = sinc_taps(q, amp.order)
    # output sample k of the window is the filter output at the last fine sample e_k of
    # its period: Σ_j taps[j] x[e_k − j]. With the fine samples as blocks of q, tap j reads
    # block (k − j // q) at position q − 1 − j % q: one matrix product per block lag.
    n_lag = -(-taps.size // q)
    t_blocks = np.zeros((n_lag, q))
    for j, tap in enumerate(taps):
        t_blocks[j // q, q - 1 - j % q] = tap
    xb = signals.reshape(signals.shape[:-1] + (n_fine // q, q))  # (..., blocks, q)
    out = np.zeros(signals.shape[:-1] + (n_t,))
    for b in range(n_lag):
        out += xb[..., n_lead - b:n_lead - b + n_t, :] @ t_blocks[b]
    return out


def digitise(sampled: np.ndarray, amp: Amplifier, rng: np.random.Generator) -> np.ndarray:
    """The converter's input-referred noise, quantisation and clipping on sampled signals.

    Parameters
    ----------
    sampled : ndarray, shape (..., n_t)
        Filtered, sampled bridge outputs [mV/V] (the filter part of :func:`acquire`).
    amp : Amplifier
    rng : numpy.random.Generator
        Noise stream.

    Returns
    -------
    ndarray, same shape
        [mV/V], on the converter's LSB grid and within its range.
    """
    noise = rng.normal(0.0, amp.noise_mvv, size=sampled.shape) if amp.noise_uv_rms > 0 \
        else None
    return quantise(sampled, amp, noise)


def quantise(sampled: np.ndarray, amp: Amplifier, noise: np.ndarray | None) -> np.ndarray:
    """:func:`digitise` with the noise already drawn (``noise`` None: none), on the
    converter's LSB grid and within its range [mV/V]. In place on one new array: the
    same operations as ``clip(round((sampled + noise) / lsb) * lsb)``, bit for bit, a
    quarter of the time (docs/results/speed.md)."""
    out = sampled.copy() if noise is None else sampled + noise
    lsb = amp.lsb_mvv
    np.divide(out, lsb, out=out)
    np.round(out, out=out)
    np.multiply(out, lsb, out=out)
    return np.clip(out, -amp.range_mvv, amp.range_mvv, out=out)
