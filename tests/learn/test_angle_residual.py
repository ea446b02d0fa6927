"""The synchronous residual's Fourier series in the wave-generator angle domain
(harmonic_coefficients(..., psi=...), reference_residual(..., psi=...)): computed order
tracking by least squares in each window's own ψ(t), checked against the steady-speed
series of the time basis.

Tolerances are set near the accuracy reached, each stated with its measured value
(python -m pytest tests/learn/test_angle_residual.py; the healthy gear at 39 N m, 0.12 s windows
at 10 kHz, default ResidualSettings: H = 48, nuisance orders 1/4, 1/3, 1/2, 1; the largest
coefficient is 0.17 mV/V).
"""


import numpy as np
import pytest
import xarray as xr

from learn.inputs import signals as sg
from swgsim.gear import dynamics as dy
from swgsim.gear import profile as pf
from swgsim.gear.chain import SimulationChain
from swgsim.gear.faults import ChainParams

N_MEAN, T_OUT = 2000.0, 39.0
RS = sg.ResidualSettings()
PSI_ORDER = 1.0 + 1.0 / RS.ratio
KW = {"psi_order": PSI_ORDER, "n_harmonics": RS.n_harmonics,
      "nuisance_orders": tuple(RS.nuisance_orders)}


@pytest.fixture(scope="module")
def chain():
    return SimulationChain()


@pytest.fixture(scope="module")
def steady(chain):
    """The healthy gear at 2000 rpm, 39 N m: one 0.12 s window (1, 5, T), its time [s]
    and ψ (1, T) [rad]."""
    sig, res = chain.simulate([ChainParams(gear=dy.rt1_size20())], N_MEAN, T_OUT, 0.3)
    t = np.arange(sig.shape[2]) / chain.settings.sample_rate_hz
    return sig, t, res.psi


@pytest.fixture(scope="module")
def ramp(chain, steady):
    """A 1000 -> 3000 rpm move at 16 667 rpm/s filling a 0.12 s window (mean 2000 rpm,
    39 N m brake): the window (1, 5, T) and its ψ (1, T) [rad]."""
    n_t, fs, hold = steady[0].shape[2], chain.settings.sample_rate_hz, 0.05
    prof = pf.Profile(pf.SpeedProfile(1000.0, (pf.Hold(hold), pf.Move(3000.0, 2000.0 / 0.12),
                                               pf.Hold(0.01))), pf.ConstantLoad(T_OUT))
    sp, rp = chain.simulate_profile([ChainParams(gear=dy.rt1_size20())], prof, 0.3)
    i0 = int(round(hold * fs))
    return sp[:, :, i0:i0 + n_t], rp.psi[:, i0:i0 + n_t]


def dataset(sig: np.ndarray, t: np.ndarray, rpm: np.ndarray) -> xr.Dataset:
    """The variables of a schema-v1 data set that reference_residual reads."""
    return xr.Dataset({"strain_signal": (("sample", "channel", "time"), sig),
                       "n_in_mean_rpm": ("sample", rpm), "n_in_rpm": ("sample", rpm)},
                      coords={"time": t})


def test_steady_angle_coefficients_match_time_basis(steady):
    """At steady speed the series in the simulated ψ (shifted to start at ψ = 0, the time
    basis' phase at t = 0) agrees with the time basis up to the speed ripple and twist that
    ψ carries (reached: 6.2e-5 mV/V complex, at h = 1 next to the order-1 nuisance term;
    amplitudes 5.1e-5; c0 4.8e-6)."""
    sig, t, psi = steady
    ref = sg.harmonic_coefficients(sig, t, np.array([N_MEAN / 60]), **KW)
    got = sg.harmonic_coefficients(sig, t, np.array([N_MEAN / 60]), **KW,
                                   psi=psi - psi[:, :1])
    assert got.shape == ref.shape == (1, 5, RS.n_harmonics + 1)
    assert np.abs(got - ref).max() <= 1e-4
    assert np.abs(np.abs(got) - np.abs(ref)).max() <= 1e-4
    assert np.abs(got[..., 0] - ref[..., 0]).max() <= 1e-5


def test_ramp_angle_coefficients_match_steady(steady, ramp):
    """Ramp window against the steady window at its mean speed (amplitudes: the phase of
    each window's start is arbitrary): the angle basis matches (reached: amplitudes 1.5e-3,
    c0 3.2e-4 mV/V; the gear torque ripples while the output accelerates), the time basis
    at the mean speed does not (amplitudes 0.83, c0 4.0e-2 mV/V)."""
    sig, t, _ = steady
    win, psi = ramp
    f0 = np.array([N_MEAN / 60])
    ref = sg.harmonic_coefficients(sig, t, f0, **KW)
    angle = sg.harmonic_coefficients(win, t, f0, **KW, psi=psi)
    time_ = sg.harmonic_coefficients(win, t, f0, **KW)
    err_a = np.abs(np.abs(angle) - np.abs(ref)).max(), np.abs(angle[..., 0] - ref[..., 0]).max()
    err_t = np.abs(np.abs(time_) - np.abs(ref)).max(), np.abs(time_[..., 0] - ref[..., 0]).max()
    assert err_a[0] <= 3e-3 and err_a[1] <= 1e-3, err_a
    assert err_t[0] >= 200 * err_a[0] and err_t[1] >= 50 * err_a[1], (err_a, err_t)


def test_ramp_residual_against_steady_reference(steady, ramp):
    """reference_residual passes ψ down: the ramp window against a steady reference (ψ of
    both given) leaves a small synthesised residual on s1..s4, the time basis a large one
    (reached, max |residual| in units of the reference RMS: s1..s4 5.5e-3 against 1.21;
    s0, the torque bridge of RMS 3.2e-3 mV/V, 0.165 against 1.68: the torque that
    accelerates the output changes its ripple, physics rather than fit error)."""
    sig, t, psi_s = steady
    win, psi_r = ramp
    ds = dataset(np.concatenate([sig, win]), t, np.array([N_MEAN, N_MEAN]))
    psi = np.concatenate([psi_s, psi_r])
    one, ref = np.array([1]), np.array([0])
    angle = sg.synthesise(sg.reference_residual(ds, one, ref, RS, psi), RS.n_points)
    time_ = sg.synthesise(sg.reference_residual(ds, one, ref, RS), RS.n_points)
    err_a, err_t = np.abs(angle).max(axis=2)[0], np.abs(time_).max(axis=2)[0]  # (5,)
    assert err_a[1:].max() <= 1e-2 and err_a[0] <= 0.2, err_a
    assert err_t[1:].min() >= 100 * err_a[1:].max() and err_t[0] >= 5 * err_a[0], (err_a, err_t)


@pytest.mark.parametrize("psi, match", [
    (np.zeros((2, 1200)), r"psi must be finite with shape \(n, T\) = \(1, 1200\)"),
    (np.full((1, 1200), np.nan), "psi must be finite"),
    (np.linspace(0.0, 3 * np.pi, 1200)[None], r"window 0: psi spans 1.5 WG revolutions"),
    (np.linspace(0.0, 1200 * 0.1, 1200)[None], "psi steps below pi / 48"),
])
def test_bad_psi_refused_in_one_line(steady, psi, match):
    sig, t, _ = steady
    with pytest.raises(ValueError, match=match) as e:
        sg.harmonic_coefficients(sig, t, np.array([N_MEAN / 60]), **KW, psi=psi)
    assert "\n" not in str(e.value)


def test_short_window_named_across_chunks(steady):
    """Windows are fitted in chunks of 32; a refused window is named by its index."""
    sig, t, psi = steady
    psi = np.repeat(psi, 40, axis=0)
    psi[35] = np.linspace(0.0, 3 * np.pi, psi.shape[1])
    with pytest.raises(ValueError, match="window 35: psi spans"):
        sg.harmonic_coefficients(np.repeat(sig, 40, axis=0), t, np.full(40, N_MEAN / 60),
                                 **KW, psi=psi)


def test_psi_refused_where_unused_and_misshapen(steady):
    sig, t, psi = steady
    with pytest.raises(ValueError, match="psi is used by the residual inputs") as e:
        sg.build_input(dataset(sig, t, np.array([N_MEAN])), "raw", psi=psi)
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match=r"psi must have shape \(windows, T\)"):
        sg.reference_residual(dataset(sig, t, np.array([N_MEAN])), np.array([0]),
                              np.array([0]), RS, psi[:, :10])
