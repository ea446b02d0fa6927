"""Sensor model and fault signatures of the whole chain (paper Sec. II-C, Fig. 6)."""

import dataclasses

import numpy as np
import pytest
from physics_reference import signals_naive, steady_motion

from swgsim.gear import dynamics as dy
from swgsim.gear.chain import MAX_TABLES, ChainSettings, SimulationChain
from swgsim.gear.faults import FAULTS, ChainParams, apply_fault
from swgsim.gear.sensors import SensorLayout

N_IN, T_OUT = 2000.0, 39.0


@pytest.fixture(scope="module")
def chain():
    return SimulationChain(SensorLayout(), settings=ChainSettings(window_s=0.06))


@pytest.fixture(scope="module")
def healthy():
    return ChainParams(gear=dy.rt1_size20())


def run(chain, variants, n_in=N_IN, t_out=T_OUT, phi0=0.4):
    sig, res = chain.simulate(variants, n_in, t_out, phi0)
    return sig, res


def rms(x, axis=-1):
    return np.sqrt(np.mean(np.square(x), axis=axis))


def test_healthy_pairs_agree(chain, healthy):
    """s1 ≈ s3 and s2 ≈ s4 on a healthy gear (symmetry of layout and ellipse, eq. 8)."""
    (s,), _ = run(chain, [healthy])
    # exact by symmetry: reached 2.4e-12, tolerance 1e-9 (round-off)
    assert rms(s[1] - s[3]) < 1e-9 * rms(s[1])
    assert rms(s[2] - s[4]) < 1e-9 * rms(s[2])
    # with gauge tolerances (this draw) the pairs less their zero offsets still agree
    # within a few per cent: reached 2.0 % and 9.4 %, bound 10 %; the offsets are each
    # bridge's own (the pairs' means differ by them)
    tol = SensorLayout().perturbed(np.random.default_rng(1))
    ch = SimulationChain(tol, settings=chain.settings, solver=chain.solver)
    (s,), _ = run(ch, [healthy])
    strain = s - tol.zero_offsets_mvv[:, None]
    assert rms(strain[1] - strain[3]) < 0.1 * rms(strain[1])
    assert rms(strain[2] - strain[4]) < 0.1 * rms(strain[2])
    (s_bal,), _ = run(SimulationChain(dataclasses.replace(tol, signals=tuple(
        dataclasses.replace(x, zero_offset_mvv=0.0) for x in tol.signals)),
        settings=chain.settings, solver=chain.solver), [healthy])
    np.testing.assert_array_equal(s, s_bal + tol.zero_offsets_mvv[:, None])
    assert np.all(np.abs(tol.zero_offsets_mvv) > 0)
    assert 0.01 < np.abs(s).max() < 1.5  # mV/V: signals of order 0.1, offsets up to 0.525


@pytest.fixture(scope="module")
def gear_chain(chain):
    """A gear's chain: its gauge tolerances and its bridges' zero offsets."""
    return SimulationChain(SensorLayout().perturbed(np.random.default_rng(7)),
                           settings=chain.settings, solver=chain.solver)


@pytest.mark.parametrize("name", sorted(FAULTS))
def test_severity_zero_is_healthy(gear_chain, healthy, name):
    """Severity 0 of every fault is the healthy gear, bit for bit, zero offsets and all."""
    assert np.all(np.abs(gear_chain.layout.zero_offsets_mvv) > 0)
    p = apply_fault(healthy, name, 0.0, 54.0)
    assert p == healthy
    a, _ = run(gear_chain, [healthy])
    b, _ = run(gear_chain, [p])
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name, sev", [("reduced_damping", 1.5), ("eccentric_wg", -0.1),
                                       ("root_tooth_crack", 1.0), ("nope", 0.1)])
def test_bad_fault_input_is_refused(healthy, name, sev):
    with pytest.raises(ValueError, match="severity|unknown fault"):
        apply_fault(healthy, name, sev, 0.0)


def test_reduced_damping_signature(chain, healthy):
    """Fig. 6a: hardly any change in the signals; the efficiency rises (Table II)."""
    (a, b), res = run(chain, [healthy, apply_fault(healthy, "reduced_damping", 0.3)])
    assert np.abs(b - a).max() < 0.01 * np.ptp(a)
    assert res.efficiency[1] > res.efficiency[0] + 0.01


def test_reduced_stiffness_signature(chain, healthy):
    """Fig. 6b: a slight change, largest in s0 (the torque bridge)."""
    (a, b), _ = run(chain, [healthy, apply_fault(healthy, "reduced_stiffness", 0.2)],
                    n_in=4000.0, t_out=7.0)
    d = rms(b - a)
    assert d.argmax() == 0
    assert d[0] < 0.05 * np.ptp(a[0]) + 0.05 * np.abs(a[0]).mean()
    assert d[0] > 1e-4


def test_eccentric_wg_signature(chain, healthy):
    """Fig. 6c: offsets of s1 and s3 (opposite), and a changed shape."""
    (a, b), _ = run(chain, [healthy, apply_fault(healthy, "eccentric_wg", 0.1, 0.0)])
    off = b.mean(axis=1) - a.mean(axis=1)
    assert abs(off[1]) > 0.1 * np.ptp(a[1]) and abs(off[3]) > 0.1 * np.ptp(a[3])
    assert np.sign(off[1]) == -np.sign(off[3])
    shape = rms((b - b.mean(1, keepdims=True)) - (a - a.mean(1, keepdims=True)))
    assert shape.max() > 1e-3  # mV/V: not an offset alone


def test_root_crack_signature(chain, healthy):
    """Fig. 6d: amplitudes change, the pair differences lose their symmetry."""
    (a, b), _ = run(chain, [healthy, apply_fault(healthy, "root_tooth_crack", 0.9, 90.0)])
    amp_change = np.abs(np.ptp(b, axis=1) / np.ptp(a, axis=1) - 1)
    assert amp_change.max() > 0.01
    d13 = rms((b[1] - b[3]) - (a[1] - a[3]))
    d24 = rms((b[2] - b[4]) - (a[2] - a[4]))
    assert max(d13, d24) > 1e-3


def test_tip_crack_signature(chain, healthy):
    """Fig. 6e: short deviations, when a mesh zone passes the cracked tooth."""
    (a, b), res = run(chain, [healthy, apply_fault(healthy, "tip_tooth_crack", 1.0, 90.0)])
    dev = np.abs(b - a).max(axis=0)
    assert dev.max() > 1e-3
    assert np.median(dev) < 0.2 * dev.max()  # localised in time, not a global change
    # deviations where a zone centre is within its half-width of the crack
    psi = res.psi[0]
    near = np.minimum(np.abs(np.angle(np.exp(1j * (psi - np.pi / 2)))),
                      np.abs(np.angle(np.exp(1j * (psi + np.pi / 2)))))
    assert np.all(dev[near > np.deg2rad(chain.settings.contact_half_width_deg)] < 1e-9)


def test_fast_chain_matches_naive_per_step_solver(chain, healthy):
    cases = [healthy, apply_fault(healthy, "eccentric_wg", 0.1, 30.0),
             apply_fault(healthy, "root_tooth_crack", 0.7, 90.0),
             apply_fault(healthy, "tip_tooth_crack", 1.0, 0.0)]
    sig, res = run(chain, cases)
    for k, p in enumerate(cases):
        naive = signals_naive(chain, p, res.psi[k, :8], res.t_out[k, :8])
        assert np.abs(sig[k, :, :8] - naive).max() <= 1e-9 * np.abs(naive).max()


def test_table_iv_b1_factor_shows_in_the_simulated_output(chain, healthy):
    """SWG model 2 of paper Table IV has b1 × 1.2: through the chain its efficiency falls
    and the flexspline winds up further, by what eq. (5) predicts for steady motion.

    Efficiency drop: reached 3.4e-4 of the predicted 0.0244, tolerance 1e-3; mean change
    of ψ = φ_in − φ_out (the wave generator's angle on the flexspline, which the gauges
    see): reached 0.26 % of the predicted −4.0e-5 rad, tolerance 0.5 %. The load stays
    held: reached 4.4e-7 N m, tolerance 1e-6 N m.
    """
    more = dataclasses.replace(healthy, gear=dataclasses.replace(
        healthy.gear, b1_nms=healthy.gear.b1_nms * 1.2))
    _, res = run(chain, [healthy, more])
    eta_a, wind_a = steady_motion(healthy.gear, N_IN, T_OUT)
    eta_b, wind_b = steady_motion(more.gear, N_IN, T_OUT)
    assert res.efficiency[1] - res.efficiency[0] == pytest.approx(eta_b - eta_a, rel=1e-3)
    assert eta_b < eta_a - 0.02
    d_psi = np.mean(res.psi[1] - res.psi[0])
    assert d_psi == pytest.approx(-(wind_b - wind_a), rel=5e-3)
    np.testing.assert_allclose(res.t_out.mean(axis=1), T_OUT, atol=1e-6)


def test_zone_tables_kept_per_group(chain, healthy):
    """The chain keeps one zone table per (root crack, tip crack) group: signals of a
    tip-cracked gear after another crack's table was kept equal a fresh chain's, and no
    more than MAX_TABLES are kept."""
    psi = np.linspace(0.0, 40.0, 30_000)[None, :]  # enough steps for a table
    t_out = np.full_like(psi, T_OUT)
    a = apply_fault(healthy, "tip_tooth_crack", 0.5, 54.0)
    b = apply_fault(healthy, "tip_tooth_crack", 0.5, 200.0)
    fresh = SimulationChain(chain.layout, settings=chain.settings, solver=chain.solver)
    chain.signals_batch([a], psi, t_out)
    np.testing.assert_array_equal(chain.signals_batch([b], psi, t_out),
                                  fresh.signals_batch([b], psi, t_out))
    assert 2 <= len(chain._tables) <= MAX_TABLES
