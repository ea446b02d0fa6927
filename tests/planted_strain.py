"""Bench-like strain data with planted effects, shared by the strain calibration's tests and
the scripts ``scripts/calibrate_strain_demo.py`` and ``scripts/strain_power.py`` (not a test
module; the scripts put ``tests/`` on their path).

The "measured" windows come from the simulation chain's standard path
(:meth:`swgsim.gear.chain.SimulationChain.simulate`: a random WG start angle per window, a
settling transient, the fast influence path), not from the calibration's model (one
steady trajectory per operating point, shifted and interpolated), so a test does not
check the model against itself. Then the planted measurement effects
(:func:`swgsim.sensing.effects.apply_sensor_effects`, with a lead of history so that filters
and shifts start in steady state), optional planted kinematic-error harmonics (through
the dynamics), optional out-of-library disturbances (:data:`HIDDEN`), and white Gaussian
noise of standard deviation ``noise_rel`` times the range of the noise-free signals.
Windows of the operating points alternate in the sequence (as on a bench that cycles
through its operating points).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.datasets import schema as dsio
from swgsim.files.ownership import atomic_write_json
from swgsim.gear.chain import SimulationChain
from swgsim.gear.dynamics import gear_with_ke, rt1_size20
from swgsim.gear.faults import NO_ROOT_CRACK, ChainParams
from swgsim.gear.sensors import SENSORS
from swgsim.sensing.effects import apply_sensor_effects

__all__ = ["PLANTED", "HIDDEN", "CleanWindows", "simulate_windows", "bench_dataset",
           "write_dataset", "expected_values"]

PLANTED: dict[str, dict[str, Any]] = {
    "offset": {"sensor_effects": [{"name": "offset",
                                   "params": {"offset_mvv": {"s1": 0.02, "s3": -0.015}}}],
               "check": {"o_s1": 0.02, "o_s3": -0.015}},
    "gain_mismatch": {"sensor_effects": [{"name": "gain_mismatch",
                                          "params": {"gain": {"s1": 1.05}}}],
                      "check": {"gain": [1.0, 1.05, 1.0, 1.0, 1.0]}},
    "gauge_misplacement": {"sensor_effects": [{"name": "gauge_misplacement",
                                               "params": {"delta_deg": {"s1": 1.5}}}],
                           "check": {"delta_deg": [0.0, 1.5, 0.0, 0.0, 0.0]}},
    "bridge_nonlinearity": {"sensor_effects": [{"name": "bridge_nonlinearity",
                                                "params": {"k_per_mvv": 0.15}}],
                            "check": {"k_per_mvv": 0.15}, "implausible": True},
    "amplifier_lowpass": {"sensor_effects": [{"name": "amplifier_lowpass",
                                              "params": {"f_c_hz": 250.0}}],
                          "check": {"f_c_hz": 250.0}},
    "ke_order3": {"ke": [{"order": 3, "amp_rad": 1.5e-4, "phase_rad": 0.7}],
                  "check": {"amplitude_rad": 1.5e-4}},
    "thermal_drift": {"sensor_effects": [{"name": "thermal_drift",
                                          "params": {"rate_mvv_per_s": {"s2": 4e-4,
                                                                        "s4": -3e-4}}}],
                      "check": {"r_s2": 4e-4, "r_s4": -3e-4}, "window_period_s": 5.0},
}
"""One planted value per library effect and what a test checks. Sizes: a few times the
noise over a channel (offsets 4σ, gain 5 %, a gauge 1.5° off), the low-pass at 250 Hz
(order 2 of 4000 rpm at 135 Hz), a KE harmonic of 1.5e-4 rad (the nominal order 2 has
1e-4 rad), a zero drift of 4e-4 mV/V/s on windows recorded every 5 s (``window_period_s``:
pass it to :func:`bench_dataset` and the calibration), within the physical ranges of
:mod:`swgcal.strain.effects`. ``"implausible": True`` marks a value outside its physical
range, planted to check that the calibration refuses it: the bridge nonlinearity at 75×
the exact quarter bridge's 2e-3 per mV/V (the physical value is far below 1 % noise)."""

HIDDEN: dict[str, dict[str, Any]] = {
    "tone_3p5": {"kind": "tone", "order": 3.5, "amplitude_mvv": 0.012, "phase_rad": 0.4},
    "square_glitch": {"kind": "square", "amplitude_mvv": 0.01, "period_s": 1.0 / 170.0},
    "crosstalk_s2_s1": {"kind": "crosstalk", "source": "s2", "target": "s1", "fraction": 0.08},
    "tone_2p7_load": {"kind": "tone", "order": 2.7, "amplitude_mvv": 0.0,
                      "amplitude_mvv_per_nm": 3e-4, "phase_rad": 1.1},
    "mains_hum": {"kind": "hum", "frequency_hz": 50.0, "amplitude_mvv": 0.015,
                  "harmonics": {"3": 0.5}},
    "load_gain_s1": {"kind": "load_gain", "channel": "s1", "gain_per_nm": 1e-3},
}
"""Out-of-library disturbances: a tone at order 3.5 of the input rotation in every channel
(locked to the rotation: its sign flips every input revolution), a zero-mean square wave
(±amplitude, 170 Hz) common to all channels at a random phase per window (DAQ
interference). The square wave is kept away (> 15 %) from k·n_in/60, k = 1..4, at both
speeds: a kinematic-error candidate re-aligns each window's input angle and can absorb
part of a tone that close to one of its frequencies (see strain.py, limitations).
For :mod:`swgcal.discovery`: crosstalk (8 % of the clean s2 signal added to
s1, as a shared ground or cable capacitance would; the order-2 pattern of one channel
leaked into another is a gain and a gauge misplacement of the target, which the library
fits, so only the torque part of s2 in s1 is out of the library: s1 into s2 is fitted as
a misplacement, s1 into s0 as an order-2 tone), a tone at order 2.7 of the
input rotation whose amplitude is proportional to the load (a bearing or a gear stage
that is not part of the model), 50 Hz mains hum with its third harmonic (half the
amplitude, phase locked to the fundamental) at a random phase per window, and a gauge
gain of s1 that grows with the load (1 + 1e-3 T_out: +7 % at 70 N m)."""


@dataclass(frozen=True)
class CleanWindows:
    """Noise-free simulated windows with a lead of history.

    Attributes
    ----------
    signals : ndarray, shape (n_windows, 5, n_lead + n_t)
        [mV/V].
    time_s : ndarray, shape (n_lead + n_t,)
        [s]; the window starts at ``time_s[n_lead]``.
    phi_in : ndarray, shape (n_windows, n_lead + n_t)
        Input angle [rad].
    n_in_rpm, t_out_nm, n_in_mean_rpm, t_out_mean_nm, efficiency : ndarray, (n_windows,)
    psi : ndarray, shape (n_windows, n_lead + n_t), optional
        WG angle relative to the flexspline [rad] (the truth an alignment is checked
        against, with ``phi_in``).
    """

    signals: np.ndarray
    time_s: np.ndarray
    n_lead: int
    phi_in: np.ndarray
    n_in_rpm: np.ndarray
    t_out_nm: np.ndarray
    n_in_mean_rpm: np.ndarray
    t_out_mean_nm: np.ndarray
    efficiency: np.ndarray
    psi: np.ndarray | None = None


def simulate_windows(chain: SimulationChain, ops: Sequence[tuple[float, float]] = (
        (2000.0, 7.0), (4000.0, 70.0)), n_per_op: int = 5, window_s: float = 0.04,
        lead_s: float = 0.02, settle_s: float = 0.05, ke: Sequence[Mapping[str, float]] = (),
        seed: int = 0) -> CleanWindows:
    """Simulate bench windows through the chain's standard path.

    Parameters
    ----------
    chain : SimulationChain
        Its layout is the "real" gear's (nominal, or perturbed for tolerances).
    ops : sequence of (n_in [rpm], T_out [N m])
    n_per_op : int
        Windows per operating point; operating points alternate in the sequence.
    window_s, lead_s, settle_s : float
        Window, history kept before it, and discarded transient [s].
    ke : sequence of mapping
        Extra kinematic-error harmonics ``{order, amp_rad, phase_rad}`` of the gear.
    seed : int
        WG start angles.
    """
    if n_per_op < 1:
        raise ValueError(f"n_per_op must be >= 1, got {n_per_op}")
    rng = np.random.default_rng(seed)
    fs = chain.settings.sample_rate_hz
    n_lead = int(round(lead_s * fs))
    n_t = int(round(window_s * fs))
    settings = dataclasses.replace(chain.settings, window_s=(n_lead + n_t) / fs,
                                   settle_s=float(settle_s))
    p = ChainParams(gear=gear_with_ke(rt1_size20(), ke))
    # a chain sharing the layout's influence, with this window length
    sim_chain = SimulationChain.from_influences(chain.layout, {NO_ROOT_CRACK: chain.influence(p)},
                                                settings)
    n_ops = len(ops)
    n_w = n_ops * n_per_op
    op_of = np.tile(np.arange(n_ops), n_per_op)  # alternate
    sig = np.empty((n_w, 5, n_lead + n_t))
    phi = np.empty((n_w, n_lead + n_t))
    psi = np.empty((n_w, n_lead + n_t))
    n_mean, t_mean, eff = np.empty(n_w), np.empty(n_w), np.empty(n_w)
    phi0 = rng.uniform(0, 2 * np.pi, n_w)
    for i, (n_in, t_out) in enumerate(ops):
        ws = np.flatnonzero(op_of == i)
        s, res = sim_chain.simulate([p] * ws.size, n_in, t_out, phi0[ws])
        sig[ws] = s
        phi[ws] = res.states[0]
        psi[ws] = res.psi
        n_mean[ws] = res.states[1, :, n_lead:].mean(axis=1) * 60 / (2 * np.pi)
        t_mean[ws] = res.t_out[:, n_lead:].mean(axis=1)
        eff[ws] = res.efficiency
    t = (np.arange(n_lead + n_t) - n_lead) / fs
    return CleanWindows(signals=sig, time_s=t, n_lead=n_lead, phi_in=phi,
                        n_in_rpm=np.array([ops[i][0] for i in op_of], float),
                        t_out_nm=np.array([ops[i][1] for i in op_of], float),
                        n_in_mean_rpm=n_mean, t_out_mean_nm=t_mean, efficiency=eff, psi=psi)


def _hidden(clean: CleanWindows, spec: Mapping[str, Any], rng: np.random.Generator) -> np.ndarray:
    n_w, _, n = clean.signals.shape
    load = np.asarray(clean.t_out_nm, float)[:, None]
    out = np.zeros_like(clean.signals)
    if spec["kind"] == "tone":
        amp = spec["amplitude_mvv"] + spec.get("amplitude_mvv_per_nm", 0.0) * load
        x = amp * np.sin(spec["order"] * clean.phi_in + spec["phase_rad"])
    elif spec["kind"] == "square":
        ph = rng.uniform(0, 1, n_w)[:, None]
        frac = np.mod(clean.time_s[None, :] / spec["period_s"] + ph, 1.0)
        x = spec["amplitude_mvv"] * np.where(frac < 0.5, 1.0, -1.0)
    elif spec["kind"] == "hum":
        ph = rng.uniform(0, 2 * np.pi, n_w)[:, None]
        arg = 2 * np.pi * spec["frequency_hz"] * clean.time_s[None, :] + ph
        x = spec["amplitude_mvv"] * np.sin(arg)
        for h, rel in spec.get("harmonics", {}).items():
            x = x + rel * spec["amplitude_mvv"] * np.sin(int(h) * arg)
    elif spec["kind"] == "crosstalk":
        a, b = SENSORS.index(spec["source"]), SENSORS.index(spec["target"])
        out[:, b] = spec["fraction"] * clean.signals[:, a]
        return out
    elif spec["kind"] == "load_gain":
        c = SENSORS.index(spec["channel"])
        out[:, c] = spec["gain_per_nm"] * load * clean.signals[:, c]
        return out
    else:
        raise ValueError(f"unknown hidden disturbance kind {spec['kind']!r}; allowed tone, "
                         "square, hum, crosstalk, load_gain")
    return np.broadcast_to(x[:, None, :], (n_w, 5, n))


def bench_dataset(clean: CleanWindows, sensor_effects: Sequence[Mapping[str, Any]] = (),
                  hidden: Sequence[Mapping[str, Any]] = (), noise_rel: float = 0.01,
                  seed: int = 1, name: str = "bench", window_period_s: float | None = None
                  ) -> tuple[Any, dict[str, Any]]:
    """A schema-v1 data set of "measured" windows from simulated ones.

    Parameters
    ----------
    sensor_effects : sequence of mapping
        Planted measurement effects (:mod:`swgsim.sensing.effects`).
    hidden : sequence of mapping
        Out-of-library disturbances (values of :data:`HIDDEN`).
    noise_rel : float, default 0.01
        White-noise standard deviation relative to the range of the noise-free signals.
    seed : int
        Noise (and glitch phases).
    window_period_s : float, optional
        Time between the starts of consecutive windows [s] (thermal drift); default the
        window length (back-to-back windows).

    Returns
    -------
    ds : xarray.Dataset
        Schema v1, fault "unknown", gear 1.
    truth : dict
        ``sigma`` (noise standard deviation [mV/V]), ``sensor_effects``, ``hidden``.
    """
    if not noise_rel >= 0:
        raise ValueError(f"noise_rel must be >= 0, got {noise_rel}")
    if window_period_s is not None and not window_period_s > 0:
        raise ValueError(f"window_period_s must be > 0 [s], got {window_period_s}")
    rng = np.random.default_rng(seed)
    n_w = clean.signals.shape[0]
    x = clean.signals.copy()
    for h in hidden:
        x = x + _hidden(clean, h, rng)
    n_t = x.shape[2] - clean.n_lead
    dt = float(clean.time_s[1] - clean.time_s[0])
    period = n_t * dt if window_period_s is None else float(window_period_s)
    y = apply_sensor_effects(x, clean.time_s, clean.n_in_mean_rpm, sensor_effects,
                             t_start_s=np.arange(n_w) * period, n_lead=clean.n_lead)
    sigma = noise_rel * float(np.ptp(y))
    y = y + sigma * rng.standard_normal(y.shape)
    meta = {
        "gear": np.ones(n_w, int), "fault": np.full(n_w, "unknown"),
        "variant": np.full(n_w, -1), "severity": np.full(n_w, np.nan),
        "position_deg": np.full(n_w, np.nan), "n_in_rpm": clean.n_in_rpm,
        "t_out_nm": clean.t_out_nm, "disturbed": np.zeros(n_w, bool),
        "reference": np.zeros(n_w, bool), "efficiency": clean.efficiency,
        "n_in_mean_rpm": clean.n_in_mean_rpm, "t_out_mean_nm": clean.t_out_mean_nm,
    }
    ds = dsio.make_dataset(y, clean.time_s[clean.n_lead:] - clean.time_s[clean.n_lead], meta,
                           {"name": name, "source": "tests/planted_strain.py",
                            "sensor_effects": list(sensor_effects), "hidden": list(hidden),
                            "noise_sigma_mvv": sigma, "window_period_s": period})
    return ds, {"sigma": sigma, "sensor_effects": list(sensor_effects), "hidden": list(hidden)}


def write_dataset(ds: Any, out_dir: str | Path) -> Path:
    """Write a data set as one shard plus ``manifest.json`` (schema v1), atomically.

    Returns
    -------
    Path
        The data-set directory (loadable with :func:`swgsim.datasets.schema.load`).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    shard = "bench.nc"
    sha = dsio.write_shard(ds, out / shard)
    n = int(ds.sizes["sample"])
    manifest = {"schema_version": dsio.SCHEMA_VERSION, "complete": True,
                "shards": {shard: {"sha256": sha, "n_samples": n, "content_sha256": sha}},
                "n_samples": n, "config": json.loads(json.dumps(
                    {k: str(v) for k, v in ds.attrs.items()}))}
    atomic_write_json(out / dsio.MANIFEST, manifest)
    return out


def expected_values(key: str, effect: Mapping[str, Any],
                    check: Mapping[str, Any] | None = None
                    ) -> tuple[dict[str, float], dict[str, float]]:
    """True values of the parameters a calibration reports for a planted effect.

    Gains and gauge angles are only observable relative to a weighted mean (the
    base model's gauge gain and the WG-angle alignment absorb the common part): the truth
    is converted with the weights the calibration reports (``effect["options"]``):
    g_c = G_c / (Σ w G / Σ w) − 1, δ_c = Δ_c − Σ w Δ / Σ w, the sums over the estimated
    channels (``options["estimable"]``; the others are not reported).

    Parameters
    ----------
    key : str
        A key of :data:`PLANTED`.
    effect : mapping
        The accepted effect's entry of ``summary["effects_added"]``.
    check : mapping, optional
        Planted values in the form of ``PLANTED[key]["check"]`` (default that entry),
        e.g. ``{"delta_deg": [0, 0, 1.5, 0, 0]}`` for another planted channel.

    Returns
    -------
    primary : dict
        Parameter -> true value, for the parameters that characterise the planted effect
        (the planted channels).
    others : dict
        Parameter -> true value of the other reported per-channel parameters.
    """
    chk = PLANTED[key]["check"] if check is None else check
    opts = effect.get("options", {})
    est = np.asarray(opts.get("estimable", np.ones(5, bool)), bool)
    w = np.asarray(opts.get("weights", np.ones(5)), float) * est
    if key == "gain_mismatch":
        g = np.asarray(chk["gain"], float)
        rel = g / (np.sum(w * g) / np.sum(w)) - 1.0
        names = [f"g_{s}" for s in SENSORS]
        planted = np.flatnonzero(g != 1.0)
    elif key == "gauge_misplacement":
        d = np.asarray(chk["delta_deg"], float)
        rel = d - np.sum(w * d) / np.sum(w)
        names = [f"delta_{s}_deg" for s in SENSORS]
        planted = np.flatnonzero(d != 0.0)
    else:
        return dict(chk), {}
    primary = {names[c]: float(rel[c]) for c in planted if est[c]}
    others = {names[c]: float(rel[c]) for c in range(5) if c not in planted and est[c]}
    return primary, others
