"""Angle channels (swgsim/sensing/angles.py): quantisation in closed form, ψ and the twist from the
recorded channels against the simulated states (dynamics.simulate at 2000 rpm, bench
output inertia), and the edge-interpolated ψ of a coarse Hall sensor at steady speed and
along a reversal (profile_dynamics.simulate_profile).

Tolerances are closed-form bounds; the figures reached are quoted in each test
(python -m pytest tests/swgsim/test_angles.py).
"""

import math

import numpy as np
import pytest

from swgsim.gear import dynamics as dy
from swgsim.gear import profile as pf
from swgsim.gear import profile_dynamics as pd
from swgsim.sensing import angles as an

N = 100.0
DT = 1e-4  # sample interval of simulate's default 10 kHz [s]


@pytest.fixture(scope="module")
def steady():
    """39 and 52 N m at 2000 rpm, two start angles (about 1 s)."""
    p = dy.rt1_size20()
    return p, dy.simulate([p, p], 2000.0, np.array([39.0, 52.0]), [0.3, 2.0])


def delta(res) -> np.ndarray:
    """Simulated output twist φ_out + φ_in / N [rad], shape (V, n_t)."""
    return res.states[2] + res.states[0] / N


def test_quantisation_within_one_count_closed_form():
    """floor quantisation: 0 <= φ − recorded < one count, on the unwrapped count; the
    resolutions in closed form (20 bits: 1296000 / 2**20 = 1.23596 arcsec)."""
    rng = np.random.default_rng(1)
    phi = rng.uniform(-300.0, 300.0, 10_000)
    for s in (an.InputAngleSensor(), an.InputAngleSensor.hall(1),
              an.InputAngleSensor.encoder(12)):
        q = an.quantise(phi, s.resolution_rad)
        err = phi - q
        assert np.all(err >= 0) and np.all(err < s.resolution_rad)
        np.testing.assert_allclose(q / s.resolution_rad, np.floor(phi / s.resolution_rad),
                                   rtol=0, atol=1e-9)
    assert an.InputAngleSensor().counts_per_rev == 24
    assert an.InputAngleSensor.hall(1).resolution_rad == pytest.approx(math.pi / 3)
    assert an.InputAngleSensor.encoder(12).counts_per_rev == 4096
    assert an.OutputEncoder().resolution_rad / an.ARCSEC == pytest.approx(1296000 / 2**20)
    m = an.measure_angles(phi, -phi / N, output_encoder=an.OutputEncoder(16))
    assert set(m) == {"phi_in", "phi_out"} and m["phi_out"].shape == phi.shape
    assert set(an.measure_angles(phi)) == {"phi_in"}


def test_psi_from_output_encoder_within_resolution(steady):
    """ψ̂ − ψ = e_out − e_in with e in [0, res): within (−res_in, res_out). With a 14-bit
    input encoder (−3.83e-4, 6.0e-6) rad, reached −3.81e-4 and 4.8e-6."""
    _, res = steady
    enc = an.OutputEncoder()
    for s in (an.InputAngleSensor(), an.InputAngleSensor.encoder(14)):
        m = an.measure_angles(res, input_sensor=s, output_encoder=enc)
        err = an.psi_estimate(m["phi_in"], m["phi_out"], N) - res.psi
        assert np.all(err > -s.resolution_rad) and np.all(err < enc.resolution_rad)


def test_psi_from_input_alone_within_twist_bound(steady):
    """Without an output encoder ψ̂ − ψ = δ − e_in (1 + 1/N): the twist, not divided by N.
    Bound (twist_bound_rad) at the mesh torque T_load / η (η the simulated efficiency):
    11.8 / 14.9 arcmin at 39 / 52 N m plus the KE's 0.58; reached 7.6 / 8.6 arcmin."""
    p, res = steady
    s = an.InputAngleSensor.encoder(14)
    m = an.measure_angles(res, input_sensor=s)
    err = an.psi_estimate(m["phi_in"], ratio=N) - res.psi
    q = s.resolution_rad * (1 + 1 / N)
    np.testing.assert_array_less(np.abs(err - delta(res)), q)  # the rest is the twist
    for v, t_load in enumerate((39.0, 52.0)):
        bound = an.twist_bound_rad(p, t_load / res.efficiency[v])
        assert np.abs(err[v]).max() < bound + q
        assert np.abs(err[v]).max() > 0.5 * bound  # the bound is not loose by orders
    # rated 52 N m at the catalogue's 77 %: 4.51e-3 rad = 15.5 arcmin
    assert an.twist_bound_rad(p, 52.0 / 0.77) / an.ARCSEC / 60 == pytest.approx(15.5, abs=0.1)


def between_edges(phi_meas: np.ndarray) -> np.ndarray:
    """Mask of samples after the first and before the last count edge, per row."""
    ch = np.diff(phi_meas, axis=-1) != 0
    first = np.argmax(ch, axis=-1)
    last = ch.shape[-1] - np.argmax(ch[..., ::-1], axis=-1)
    i = np.arange(phi_meas.shape[-1])
    return (i > first[:, None]) & (i < last[:, None])


def test_edge_interpolated_psi_at_steady_speed(steady):
    """24-count Hall sensor (15°) at 2000 rpm: between edges the angle error is at most
    ω Δt / 2 = 0.0105 rad (edge time to half a sample; reached 0.0101, the speed ripple is
    0.07 % peak to peak); over the whole window incl. the extrapolated ends at most ω Δt (reached
    0.0104). RMS 0.0049 rad against 0.076 of the raw count. ψ adds the twist."""
    _, res = steady
    hall = an.InputAngleSensor()
    m = an.measure_angles(res, input_sensor=hall)
    sm = an.edge_interpolate(res.time, m["phi_in"], hall.resolution_rad)
    err = sm - res.states[0]
    w = np.abs(res.states[1]).max()
    assert np.abs(err[between_edges(m["phi_in"])]).max() <= 1.02 * w * DT / 2
    assert np.abs(err).max() <= w * DT
    assert err.std() < 0.1 * (m["phi_in"] - res.states[0]).std()
    psi = an.psi_smooth(res.time, m["phi_in"], hall, ratio=N)
    np.testing.assert_array_less(np.abs(psi - res.psi - delta(res)), w * DT * (1 + 1 / N))


def test_edge_interpolated_psi_along_a_reversal():
    """1000 -> -1000 rpm at 2e4 rpm/s, load step 7 -> 39 N m. Everywhere within one count
    (reached 0.207 of 0.262 rad: near the reversal the edges are sparse). Where no sample
    within one count period T = res / ω_min (ω_min = 300 rpm) is slower than ω_min, the
    error is at most ω Δt / 2 + a T² / 8 = 0.024 rad (edge timing plus the acceleration a
    within one count; reached 0.009)."""
    p = dy.rt1_size20()
    sp = pf.SpeedProfile(1000.0, (pf.Hold(0.02), pf.Move(-1000.0, 2e4), pf.Hold(0.02)))
    r = pd.simulate_profile([p], pf.Profile(sp, pf.LoadSteps(7.0, ((0.01, 39.0),))), 0.3)
    hall = an.InputAngleSensor()
    res_rad = hall.resolution_rad
    m = an.measure_angles(r, input_sensor=hall)
    err = (an.edge_interpolate(r.time, m["phi_in"], res_rad) - r.states[0])[0]
    assert np.abs(err).max() < res_rad
    w_min = 300.0 * dy.RPM
    t_cnt = res_rad / w_min
    t_slow = r.time[np.abs(r.w_d) < w_min]
    moving = np.abs(r.time[:, None] - t_slow[None, :]).min(axis=1) > t_cnt
    assert moving.sum() > 0.6 * r.time.size
    tol = np.abs(r.states[1]).max() * DT / 2 + 2e4 * dy.RPM * t_cnt**2 / 8
    assert np.abs(err[moving]).max() <= tol
    psi = an.psi_smooth(r.time, m["phi_in"], hall, ratio=N)[0]
    np.testing.assert_array_less(np.abs(psi - r.psi[0] - delta(r)[0])[moving],
                                 tol * (1 + 1 / N))


def test_twist_estimate_against_the_simulated_twist(steady):
    """δ̂ − δ = −e_out − e_in / N, within (−res_out − res_in / N, 0]. The model's mean twist
    at 52 N m, 2000 rpm is 8.13 arcmin: the cubic stiffness solved at the mesh torque
    T_load / η, 8.14 (within 0.2 %; tolerance 1 %), below the catalogue-linear
    52 N m / (c² k1) = 11.5 arcmin."""
    p, res = steady
    s, enc = an.InputAngleSensor.encoder(14), an.OutputEncoder()
    m = an.measure_angles(res, input_sensor=s, output_encoder=enc)
    err = an.twist_estimate(m["phi_in"], m["phi_out"], N) - delta(res)
    assert np.all(err <= 1e-12) and np.all(err > -enc.resolution_rad - s.resolution_rad / N)
    c, k1, k2 = p.c_out, p.k1_nm_per_rad, p.k2_nm_per_rad3
    mean52 = an.twist_estimate(m["phi_in"], m["phi_out"], N)[1].mean()
    lin = 52.0 / (c * c * k1)
    assert lin / an.ARCSEC / 60 == pytest.approx(11.49, abs=0.01)
    x = np.roots([k2, 0.0, k1, -52.0 / res.efficiency[1] / c])  # Δφ_k of c T_stiff = T / η
    static = float(x[np.isclose(x.imag, 0)].real.max()) / c
    assert mean52 == pytest.approx(static, rel=0.01)
    assert mean52 / an.ARCSEC / 60 == pytest.approx(8.13, abs=0.05)


def test_bad_input_is_refused():
    """One-line errors naming the key."""
    for make, key in ((lambda: an.InputAngleSensor(0), "counts_per_rev"),
                      (lambda: an.InputAngleSensor(2.5), "counts_per_rev"),
                      (lambda: an.InputAngleSensor.hall(0), "pole_pairs"),
                      (lambda: an.InputAngleSensor.encoder(7), "bits"),
                      (lambda: an.InputAngleSensor.encoder(33), "bits"),
                      (lambda: an.OutputEncoder(40), "bits"),
                      (lambda: an.OutputEncoder(True), "bits"),
                      (lambda: an.OutputEncoder(20, ""), "source"),
                      (lambda: an.measure_angles([0.0, np.nan]), "phi"),
                      (lambda: an.measure_angles([0.0], output_encoder=an.OutputEncoder()),
                       "phi_out"),
                      (lambda: an.psi_estimate([0.0, 1.0], [0.0]), "phi_out_meas"),
                      (lambda: an.psi_estimate([0.0], ratio=0.0), "ratio"),
                      (lambda: an.twist_estimate([0.0], None), "phi_out_meas"),
                      (lambda: an.twist_bound_rad(dy.rt1_size20(), -1.0), "mesh_torque_nm"),
                      (lambda: an.quantise([0.0], 0.0), "resolution_rad"),
                      (lambda: an.edge_interpolate([0.0, 0.0], [0.0, 0.0], 0.1), "time")):
        with pytest.raises(ValueError, match=key) as e:
            make()
        assert "\n" not in str(e.value)


def _edges_reference(t: np.ndarray, phi: np.ndarray, res: float) -> np.ndarray:
    """edge_interpolate of one row on arrays, as it was written before the compiled loop
    (swgsim.sensing.angles._edges_row)."""
    k = np.rint(phi / res).astype(np.int64)
    dk = np.diff(k)
    idx = np.flatnonzero(dk)
    if idx.size == 0:
        return phi.copy()
    m = np.abs(dk[idx])
    j = np.repeat(idx, m)
    step = np.sign(dk[idx])
    within = np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m)
    bound = np.repeat(k[idx], m) + np.where(np.repeat(step, m) > 0, within + 1, -within)
    te = t[j] + (within + 0.5) / np.repeat(m, m) * (t[j + 1] - t[j])
    ang = bound * res
    if te.size == 1:
        return np.full_like(phi, ang[0])

    def end_slope(te, ang):
        d = np.sign(np.diff(ang[:5]))
        k = int(np.argmax(d != d[0])) if np.any(d != d[0]) else d.size
        return float((ang[k] - ang[0]) / (te[k] - te[0]))

    out = np.interp(t, te, ang)
    lo, hi = t < te[0], t > te[-1]
    out[lo] = ang[0] + (t[lo] - te[0]) * end_slope(te, ang)
    out[hi] = ang[-1] + (t[hi] - te[-1]) * end_slope(-te[::-1], ang[::-1]) * -1.0
    return out


def test_compiled_edge_interpolation_matches_the_array_form():
    """The compiled edge interpolation equals its array form to rounding on rows that run
    steadily, reverse, stand still, cross several counts in one sample, and hold no edge
    or a single one."""
    res = 2 * np.pi / 24
    t = np.arange(600) / 1e4
    rng = np.random.default_rng(11)
    rows = [2 * np.pi * 33.0 * t + 0.3,  # steady, 2000 rpm
            0.8 * np.sin(2 * np.pi * 12.0 * t),  # reversals
            np.where(t < 0.03, 0.1, 0.1 + 40.0 * (t - 0.03)),  # standstill, then moving
            2 * np.pi * 500.0 * t,  # several counts per sample
            np.full(t.size, 0.2),  # no edge
            np.where(t < 0.02, 0.1, 0.2),  # one edge
            np.cumsum(rng.normal(0.0, 0.05, t.size))]  # random walk
    phi = np.floor(np.array(rows) / res) * res
    got = an.edge_interpolate(t, phi, res)
    for row, g in zip(phi, got, strict=True):
        np.testing.assert_allclose(g, _edges_reference(t, row, res), rtol=0, atol=1e-12)
