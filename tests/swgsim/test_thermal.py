"""Joint temperature, friction against temperature and run-in (swgsim.gear.thermal), and the
bridges' temperature drift and the temperature sensor (swgsim.sensing.bridge_drift): closed forms,
a fixed-step reference, identities, refusals and seeded draws."""

import dataclasses
import time

import numpy as np
import pytest
from physics_reference import apply_bridge_drift

from swgsim.gear import thermal as th
from swgsim.gear.dynamics import RPM, Batch, rt1_size20, steady_state
from swgsim.sensing import bridge_drift as bd

GEAR = rt1_size20()
FLAT = th.JointThermal(ambient_swing_k=0.0, run_h_per_day=24.0)  # constant hall, no stops
R_TH = FLAT.r_th_k_per_w  # [K/W]


# ---------------------------------------------------------------- joint temperature
def test_warm_up_from_cold_is_the_first_order_step_response():
    h = np.array([0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0])
    t = th.joint_temperature(h, np.full(h.shape, 30.0), FLAT)
    exact = 20.0 + R_TH * 30.0 * (1.0 - np.exp(-h / 0.5))
    # exact updates composed: rounding only (reached 0 K; 1e-12 leaves room for other
    # platforms' exp)
    np.testing.assert_allclose(t, exact, rtol=0, atol=1e-12)


def test_cooling_over_a_stop_is_the_exponential_decay():
    cfg = th.JointThermal(tau_min=240.0, ambient_swing_k=0.0, run_h_per_day=16.0)
    assert th.wall_clock_h([0.0, 8.0, 16.0, 20.0, 32.0], 16.0).tolist() == [
        0.0, 8.0, 24.0, 28.0, 48.0]
    h = np.array([0.0, 15.0, 16.0])  # the last: next morning, after 8 h standing
    t = th.joint_temperature(h, np.full(3, 25.0), cfg)
    rise = R_TH * 25.0
    end_of_day = 20.0 + rise * (1.0 - np.exp(-16.0 / 4.0))
    assert t[1] == pytest.approx(20.0 + rise * (1.0 - np.exp(-15.0 / 4.0)), abs=1e-12)
    # reached 7e-15 and 0 K; margin for other platforms' exp
    assert t[2] == pytest.approx(20.0 + (end_of_day - 20.0) * np.exp(-8.0 / 4.0), abs=1e-12)


def test_every_day_starts_cold_after_a_stop_of_many_time_constants():
    cfg = dataclasses.replace(FLAT, run_h_per_day=16.0)  # 8 h stop = 16 time constants
    h = np.arange(0.0, 3 * 16.0, 0.25)
    t = th.joint_temperature(h, np.full(h.shape, 30.0), cfg)
    rise = th.steady_rise_k(30.0, cfg)
    starts = t[np.isin(h, [16.0, 32.0])]
    ends = t[np.isin(h, [15.75, 31.75])]
    np.testing.assert_allclose(ends, 20.0 + rise, atol=1e-12)  # e^-31.5 of the rise: 4e-13
    # what is left of the rise after the stop: e^-16 of it (2.0e-6 K), reached to 5e-10
    # of it (rounding of T, 1e-15 K)
    np.testing.assert_allclose(starts - 20.0, rise * np.exp(-16.0), rtol=1e-6)


def test_steady_rise_is_r_th_times_the_loss():
    assert th.steady_rise_k(32.5, FLAT) == pytest.approx(R_TH * 32.5, rel=1e-15)
    t = th.joint_temperature([0.0, 50.0], [32.5, 32.5], FLAT)  # 100 time constants
    assert t[1] == pytest.approx(20.0 + R_TH * 32.5, abs=1e-12)


def _reference(h, p, cfg, dt_h=1.0 / 60.0):
    """RK4 at a fixed step on wall-clock time; every event lies on the step grid."""
    wall = th.wall_clock_h(h, cfg.run_h_per_day)
    n = int(round(wall[-1] / dt_h))
    temp, out = float(th.ambient_temperature(0.0, cfg)), {}
    k_w = np.rint(wall / dt_h).astype(int)
    for k in range(n + 1):
        out[k] = temp
        t = k * dt_h
        i = max(np.searchsorted(k_w, k, side="right") - 1, 0)
        on = np.mod(t + 0.5 * dt_h, 24.0) < cfg.run_h_per_day
        heat = cfg.r_th_k_per_w * p[i] * on

        def f(tt, x, heat=heat):
            return (heat + th.ambient_temperature(tt, cfg) - x) * 60.0 / cfg.tau_min

        a = f(t, temp)
        b = f(t + dt_h / 2, temp + dt_h / 2 * a)
        c = f(t + dt_h / 2, temp + dt_h / 2 * b)
        d = f(t + dt_h, temp + dt_h * c)
        temp = temp + dt_h / 6 * (a + 2 * b + 2 * c + d)
    return np.array([out[k] for k in k_w])


def test_swing_ramps_stops_and_loss_steps_match_a_fixed_step_reference():
    cfg = th.JointThermal(tau_min=90.0, ambient_swing_k=4.0, run_h_per_day=16.0,
                          ambient_points=[[0.0, 0.0], [30.0, 5.0], [40.0, 2.0]])
    h = np.arange(0.0, 40.0, 0.5)
    p = 20.0 + 15.0 * np.sin(h)  # a different loss every window
    fast = th.joint_temperature(h, p, cfg)
    # RK4 at 1 min against the exact updates: 9.3e-10 K, falling 16-fold per halved step
    # (1.5e-8 K at 2 min, 7.7e-8 K at 3 min: order 4), so the reference's own error
    np.testing.assert_allclose(fast, _reference(h, p, cfg), rtol=0, atol=2e-9)


NET = th.ThermalNetwork()


def test_a_two_node_joint_at_steady_duty_sits_at_its_resistances_closed_form():
    """Issue 83: the grease sits R_gh P_loss above the housing, the housing (P_loss +
    P_cu + P_drive) R_ha above the hall; the joint at the gear's loss warms as one node."""
    cfg = dataclasses.replace(FLAT, network=NET)
    h = np.array([0.0, 0.5, 50.0])  # 100 of the housing's time constants at the end
    g, hs = th.network_temperatures(h, np.full(3, 30.0), np.full(3, 0.5), cfg)
    p_cu = (0.5 / NET.motor_km_nm_per_sqrt_w) ** 2 + NET.drive_w
    r_ha = R_TH - NET.grease_r_k_per_w
    assert hs[-1] == pytest.approx(20.0 + (30.0 + p_cu) * r_ha, abs=1e-9)
    assert g[-1] == pytest.approx(hs[-1] + 30.0 * NET.grease_r_k_per_w, abs=1e-9)
    assert g[0] == hs[0] == 20.0 and g[1] > hs[1]  # the grease leads in a warm-up


def _network_reference(h, p, tq, cfg, dt_h=1.0 / 240.0):
    """RK4 at a fixed step of 15 s on wall-clock time, the hall's true swing and ramps."""
    net = cfg.network
    wall = th.wall_clock_h(h, cfg.run_h_per_day)
    r_ha = cfg.r_th_k_per_w - net.grease_r_k_per_w
    c_h, c_g = cfg.tau_min * 60.0 / r_ha, net.grease_c_j_per_k
    k_w = np.rint(wall / dt_h).astype(int)
    x, out = np.full(2, float(th.ambient_temperature(0.0, cfg))), {}
    for k in range(k_w[-1] + 1):
        out[k] = x
        t = k * dt_h
        i = max(np.searchsorted(k_w, k, side="right") - 1, 0)
        on = np.mod(t + 0.5 * dt_h, 24.0) < cfg.run_h_per_day
        gg = 1.0 / (net.grease_r_k_per_w * (1.0 if on else net.standstill_factor))
        pg, ph = p[i] * on, ((tq[i] / net.motor_km_nm_per_sqrt_w) ** 2 + net.drive_w) * on

        def f(tt, y, gg=gg, pg=pg, ph=ph):
            amb = th.ambient_temperature(tt, cfg)
            return 3600.0 * np.array([(pg - gg * (y[0] - y[1])) / c_g,
                                      (ph + gg * (y[0] - y[1]) - (y[1] - amb) / r_ha) / c_h])

        a = f(t, x)
        b = f(t + dt_h / 2, x + dt_h / 2 * a)
        c = f(t + dt_h / 2, x + dt_h / 2 * b)
        d = f(t + dt_h, x + dt_h * c)
        x = x + dt_h / 6 * (a + 2 * b + 2 * c + d)
    return np.array([out[k] for k in k_w])


def test_a_two_node_joint_through_days_stops_and_a_hall_matches_a_fixed_step_reference():
    """Exact steps with the hall held at each interval's midpoint, against RK4 at 15 s on
    the true swing: within 0.02 K through two days with stops, a ramp and changing loads;
    at a stop the grease cools into the housing (standstill_factor)."""
    cfg = th.JointThermal(tau_min=40.0, ambient_swing_k=4.0, run_h_per_day=16.0,
                          ambient_points=[[0.0, 0.0], [30.0, 5.0]], network=NET)
    h = np.arange(0.0, 32.0, 0.25)
    p, tq = 20.0 + 15.0 * np.sin(h), 0.4 + 0.2 * np.cos(h)
    g, hs = th.network_temperatures(h, p, tq, cfg)
    ref = _network_reference(h, p, tq, cfg)
    np.testing.assert_allclose(g, ref[:, 0], rtol=0, atol=0.02)
    np.testing.assert_allclose(hs, ref[:, 1], rtol=0, atol=0.02)
    after = int(np.searchsorted(h, 16.0))  # the first window after the night's stop
    assert abs(g[after] - hs[after]) < 0.05 < g[after - 1] - hs[after - 1]


def test_a_two_node_joint_refuses_a_grease_resistance_beyond_the_joints():
    cfg = dataclasses.replace(FLAT, network=th.ThermalNetwork(grease_r_k_per_w=0.3))
    with pytest.raises(ValueError, match=r"network.grease_r_k_per_w must lie below"):
        cfg.check("thermal")
    with pytest.raises(ValueError, match=r"network.standstill_factor must lie in \[1, 1000\]"):
        th.ThermalNetwork(standstill_factor=0.5).check("network")


def test_a_hundred_thousand_windows_take_well_under_a_second():
    h = np.sort(np.random.default_rng(1).uniform(0.0, 1000.0, 100_000))
    cfg = th.JointThermal(ambient_points=[[0.0, 0.0], [48.0, 10.0]])
    t0 = time.perf_counter()
    t = th.joint_temperature(h, np.full(h.shape, 30.0), cfg)
    assert time.perf_counter() - t0 < 1.0  # 0.03-0.05 s measured on the 2-core machine
    assert np.all(np.isfinite(t)) and t.max() < 20.0 + 10.0 + 3.0 + 18.0 + 1e-9


@pytest.mark.parametrize("call, key", [
    (lambda: th.JointThermal(run_h_per_day=0.0).check(), "JointThermal.run_h_per_day"),
    (lambda: th.JointThermal(r_th_k_per_w=-1.0).check("life.thermal"),
     "life.thermal.r_th_k_per_w"),
    (lambda: th.JointThermal(ambient_points=[[5.0, 1.0], [5.0, 2.0]]).check(),
     "ambient_points"),
    (lambda: th.JointThermal(ambient_points=[[0.0, 0.0], [10.0, 500.0]]).check("hall"),
     r"hall: the hall reaches 17..523 °C .* within \[-40, 150\] °C"),
    (lambda: th.JointThermal(ambient_c=-45.0).check(), "reaches -48..-42 °C"),
    (lambda: th.joint_temperature([0.0], [1.0], th.JointThermal(tau_min=0.0)),
     "JointThermal.tau_min"),
    (lambda: th.joint_temperature([0.0, 2.0, 1.0], [1.0, 1.0, 1.0]), "must not decrease"),
    (lambda: th.joint_temperature([0.0, 1.0], [1.0]), "share a shape"),
    (lambda: th.joint_temperature([0.0, 1.0], [1.0, -1.0]), "loss_w"),
    (lambda: th.wall_clock_h([-1.0], 16.0), "operating_h"),
])
def test_bad_thermal_input_is_refused_in_one_line(call, key):
    with pytest.raises(ValueError, match=key) as e:
        call()
    assert "\n" not in str(e.value)


# ---------------------------------------------------------------- viscosity, friction
def test_viscosity_law_at_its_defining_values_and_range():
    assert th.viscosity_ratio(20.0) == 1.0
    assert th.viscosity_ratio(0.0) == pytest.approx(np.exp(0.7), rel=1e-15)
    assert th.viscosity_ratio(40.0) == pytest.approx(np.exp(-0.7), rel=1e-15)
    assert th.viscosity_ratio(60.0, ref_c=40.0) == pytest.approx(np.exp(-0.7), rel=1e-15)
    for bad in (-40.5, 150.5, np.nan):
        with pytest.raises(ValueError, match=r"temp_c must lie in \[-40, 150\] °C"):
            th.viscosity_ratio([20.0, bad])


def test_friction_scale_follows_the_catalogue_trend_at_the_rated_point():
    eta = {t: float(th.steady_efficiency(th.gear_at_temperature(GEAR, t), 2000.0, 52.0))
           for t in (0.0, 20.0, 40.0)}
    assert eta[20.0] == pytest.approx(0.77, abs=1e-12)  # the fit of rt1_size20
    # the roughly 69 / 82 % (rounded, not read from the catalogue): reached
    # 70.48 % (the fitted model's viscous share of the rated loss is 56 %, the issue's
    # estimate took 60 %) and 81.74 %
    assert abs(eta[0.0] - 0.69) < 0.02 and abs(eta[40.0] - 0.82) < 0.01
    nl = {t: float(th.no_load_torque_nm(th.gear_at_temperature(GEAR, t), 2000.0))
          for t in (0.0, 20.0, 40.0)}
    assert nl[20.0] == pytest.approx(0.105, rel=1e-12)  # the catalogue's running torque
    for t, target in ((0.0, 1.6), (40.0, 0.63)):
        assert nl[t] / nl[20.0] == pytest.approx(float(th.friction_scale(t)), rel=1e-12)
        assert abs(nl[t] / nl[20.0] - target) < 0.01  # reached 0.005 and 0.003


def test_steady_closed_form_matches_the_models_steady_state():
    n = np.array([500.0, 2000.0, 4000.0])[:, None]
    t = np.array([7.0, 39.0, 70.0])[None, :]
    for gear in (GEAR, th.gear_at_temperature(GEAR, 0.0, run_in=1.1)):
        b = Batch.of([gear] * 9)
        x = steady_state(b, (n * RPM * np.ones_like(t)).ravel(), (t * np.ones_like(n)).ravel(),
                         np.zeros(9))
        t_stiff = x[4] * gear.ki_nm / gear.tan_alpha_in  # the PI integrator balances it
        eta_fp = (t * np.ones_like(n)).ravel() / (gear.c_out * t_stiff)
        # 20 fixed-point steps of dynamics.steady_state: converged to 1e-16
        np.testing.assert_allclose(th.steady_efficiency(gear, n, t).ravel(), eta_fp,
                                   rtol=1e-12)
    p_out = t * n * RPM / GEAR.ratio
    loss = th.loss_power_w(GEAR, n, t)
    assert loss.shape == (3, 3)
    np.testing.assert_allclose(loss, p_out * (1 / th.steady_efficiency(GEAR, n, t) - 1),
                               rtol=1e-12)
    with pytest.raises(ValueError, match="n_in_rpm"):
        th.loss_power_w(GEAR, 0.0, 7.0)


def test_gear_at_reference_and_run_in_is_the_input_gear():
    assert th.gear_at_temperature(GEAR, 20.0, 1.0) == GEAR
    cold = th.gear_at_temperature(GEAR, 0.0, run_in=1.1)
    s = float(th.friction_scale(0.0)) * 1.1
    assert cold.b1_nms == pytest.approx(GEAR.b1_nms * s, rel=1e-15)
    assert cold.b3_nm == pytest.approx(GEAR.b3_nm * s, rel=1e-15)
    assert cold.mu == pytest.approx(GEAR.mu * 1.1, rel=1e-15)
    assert dataclasses.replace(cold, b0_nm=GEAR.b0_nm, b1_nms=GEAR.b1_nms,
                               b2_nms3=GEAR.b2_nms3, b3_nm=GEAR.b3_nm, mu=GEAR.mu) == GEAR
    with pytest.raises(ValueError, match="run_in"):
        th.gear_at_temperature(GEAR, 20.0, run_in=0.0)


def test_run_in_factor_limits_and_efficiency_gain():
    assert th.run_in_factor(0.0) == pytest.approx(1.16, rel=1e-15)
    assert th.run_in_factor(30.0) == pytest.approx(1 + 0.16 * np.exp(-1.0), rel=1e-15)
    assert th.run_in_factor(1e5) == 1.0
    assert np.all(np.diff(th.run_in_factor(np.linspace(0.0, 200.0, 50))) < 0)
    new = th.gear_at_temperature(GEAR, 20.0, run_in=float(th.run_in_factor(0.0)))
    gain = 0.77 - float(th.steady_efficiency(new, 2000.0, 52.0))
    assert abs(gain - 0.03) < 0.001  # the issue's +3 points; reached 0.0003
    with pytest.raises(ValueError, match="drop"):
        th.run_in_factor(0.0, drop=-0.1)


# ---------------------------------------------------------------- bridge drift
def _signals(rng, w=3, n_t=50):
    return 0.1 * rng.standard_normal((w, 5, n_t))


def test_span_drift_is_a_common_mode_gain():
    s = _signals(np.random.default_rng(0))
    temp = np.array([20.0, 35.0, 5.0])
    out = apply_bridge_drift(s, temp, np.zeros(5), np.full(5, 4e-4))
    gain = np.broadcast_to((1 + 4e-4 * (temp - 20.0))[:, None, None], s.shape)
    np.testing.assert_allclose(out / s, gain, rtol=1e-13)
    assert np.array_equal(out[0], s[0])  # at the reference: unchanged


def test_zero_drift_is_additive_and_independent_of_the_signal():
    rng = np.random.default_rng(1)
    zero = np.array([2e-4, -1e-4, 1.4e-4, 0.0, -3e-4])
    temp = np.array([20.0, 40.0, -10.0])
    d = [apply_bridge_drift(s, temp, zero, np.zeros(5)) - s
         for s in (_signals(rng), _signals(rng))]
    np.testing.assert_allclose(d[0], d[1], atol=1e-15)
    np.testing.assert_allclose(d[0][:, :, 0], zero[None, :] * (temp - 20.0)[:, None],
                               atol=1e-15)


@pytest.mark.parametrize("args, key", [
    ((np.zeros((2, 4, 10)), np.zeros(2), np.zeros(5), np.zeros(5)), "signals"),
    ((np.zeros((2, 5, 10)), np.zeros(3), np.zeros(5), np.zeros(5)), "temp_c"),
    ((np.zeros((2, 5, 10)), np.zeros(2), np.zeros(4), np.zeros(5)), "zero_mvv_per_k"),
    ((np.zeros((2, 5, 10)), np.zeros(2), np.zeros(5), [0, 0, 0, 0, np.nan]), "span_per_k"),
])
def test_bad_bridge_input_is_refused_in_one_line(args, key):
    with pytest.raises(ValueError, match=key) as e:
        apply_bridge_drift(*args)
    assert "\n" not in str(e.value)


def test_drift_defaults_and_seeded_draws():
    cfg = bd.BridgeDrift()
    # 1e3 GF/4 sqrt(n) sigma: full bridge 2e-4, half bridges 1.41e-4 mV/V per K
    np.testing.assert_allclose(cfg.zero_sd_mvv_per_k,
                               [2e-4] + [np.sqrt(2) * 1e-4] * 4, rtol=1e-14)
    assert cfg.span_mean_per_k == pytest.approx(2.9e-4 + 1e-4 - 3.3e-5, rel=1e-14)
    a = bd.draw_bridge_drift(cfg, np.random.default_rng(7))
    b = bd.draw_bridge_drift(cfg, np.random.default_rng(7))
    c = bd.draw_bridge_drift(cfg, np.random.default_rng(8))
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])
    assert a[0].shape == a[1].shape == (5,)
    rng = np.random.default_rng(3)
    draws = np.array([np.concatenate(bd.draw_bridge_drift(cfg, rng)) for _ in range(4000)])
    # sd of an sd estimate from 4000 draws: 1.1 %; 5 % is 4.5 sigma
    np.testing.assert_allclose(draws.std(axis=0),
                               np.concatenate([cfg.zero_sd_mvv_per_k, [5e-5] * 5]),
                               rtol=0.05)
    with pytest.raises(ValueError, match="BridgeDrift.span_sd_per_k"):
        bd.BridgeDrift(span_sd_per_k=-1.0).check()


# ---------------------------------------------------------------- temperature sensor
def test_sensor_quantises_and_adds_seeded_noise():
    true = np.linspace(18.0, 42.0, 1001)
    quiet = bd.measure_temperature(true, bd.TemperatureSensor(0.1, 0.0),
                                   np.random.default_rng(0))
    assert quiet.dtype == np.float64 and quiet.shape == true.shape
    np.testing.assert_allclose(quiet * 10, np.round(quiet * 10), atol=1e-9)
    assert np.max(np.abs(quiet - true)) <= 0.05 + 1e-12
    sensor = bd.TemperatureSensor()
    r1 = bd.measure_temperature(true, sensor, np.random.default_rng(5))
    r2 = bd.measure_temperature(true, sensor, np.random.default_rng(5))
    assert np.array_equal(r1, r2)
    raw = bd.measure_temperature(np.full(20_000, 30.0), bd.TemperatureSensor(0.0, 0.05),
                                 np.random.default_rng(6))
    assert raw.std() == pytest.approx(0.05, rel=0.03)  # 1 % sd of the estimate
    with pytest.raises(ValueError, match="TemperatureSensor.resolution_k"):
        bd.TemperatureSensor(resolution_k=-0.1).check()


@pytest.mark.parametrize("form", th.MONOTONE_FORMS)
def test_every_friction_law_is_anchored_at_20_and_40_degc_and_falls_smoothly(form):
    t = np.linspace(-40.0, 150.0, 1901)
    for r in (0.3, 0.63, 0.8, 1.0):
        phi = th.FrictionLaw(form, r).factor(t)
        assert th.FrictionLaw(form, r).factor(20.0) == pytest.approx(1.0, abs=1e-15)
        assert th.FrictionLaw(form, r).factor(40.0) == pytest.approx(r, rel=1e-12)
        assert np.all(phi > 0) and np.all(np.diff(phi) <= 0)  # positive, monotone
    far = th.FrictionLaw(form, 0.63).factor([0.0, 80.0])
    assert far[0] > 1.3 and far[1] < 0.6  # each law warmer: less friction, colder: more


def test_the_default_friction_law_is_the_viscosity_law_and_the_forms_differ_off_the_anchors():
    t = np.array([-20.0, 0.0, 20.0, 40.0, 60.0, 100.0])
    np.testing.assert_array_equal(th.FrictionLaw().factor(t), th.friction_scale(t))
    at_80 = {f: float(th.FrictionLaw(f).factor(80.0)) for f in th.MONOTONE_FORMS}
    assert len({round(v, 2) for v in at_80.values()}) == 3  # three laws, not one


def test_a_u_shaped_law_falls_to_its_minimum_then_rises():
    """The Coulomb term's law whose slope changes sign (issue 83): anchored as every law,
    falling up to minimum_c, rising beyond it, floored."""
    law = th.FrictionLaw("u_shaped", 0.63, 60.0)
    t = np.linspace(-40.0, 150.0, 1901)
    phi = law.factor(t)
    assert law.factor(20.0) == pytest.approx(1.0, abs=1e-15)
    assert law.factor(40.0) == pytest.approx(0.63, rel=1e-12)
    m = int(np.argmin(phi))
    assert t[m] == pytest.approx(60.0, abs=0.1)
    assert np.all(np.diff(phi[:m]) < 0) and np.all(np.diff(phi[m + 1:]) > 0)
    assert phi.min() >= th.FACTOR_FLOOR and float(law.factor(100.0)) > 0.63


def test_viscous_and_coulomb_factors_act_on_their_own_terms():
    """steady_efficiency with a Coulomb factor: the same as one factor where both are
    equal, and at no load the loss moves by each term's share alone."""
    n, t = np.array([500.0, 2000.0, 4000.0]), np.array([0.0, 26.0, 52.0])
    one = th.steady_efficiency(GEAR, n[:, None], t[None, :], 0.7, 0.9)
    both = th.steady_efficiency(GEAR, n[:, None], t[None, :], 0.7, 0.9, coulomb=0.7)
    np.testing.assert_allclose(both, one, rtol=1e-14)
    v = n * RPM / (GEAR.ratio * np.sin(GEAR.alpha_tooth_rad))
    s = np.tanh(v / GEAR.v_smooth_rad_s)
    d = 1.0 - GEAR.mu * s / (np.sin(GEAR.alpha_tooth_rad) * np.cos(GEAR.alpha_tooth_rad))
    b0, visc = GEAR.b0_nm * s / d, (GEAR.b1_nms * v + GEAR.b2_nms3 * v**3) / d
    loss = {}
    for fv, fc in ((1.0, 1.0), (0.5, 1.0), (1.0, 0.5)):  # no load: (fc b0 s + fv (...)) / d
        tf = th._steady_friction(GEAR, n, 0.0, fv, 1.0, coulomb=fc)[0]
        np.testing.assert_allclose(tf, fc * b0 + fv * visc, rtol=1e-14)
        loss[(fv, fc)] = tf
    np.testing.assert_allclose(loss[(1.0, 1.0)] - loss[(0.5, 1.0)], 0.5 * visc, rtol=1e-12)
    np.testing.assert_allclose(loss[(1.0, 1.0)] - loss[(1.0, 0.5)], 0.5 * b0, rtol=1e-12)


@pytest.mark.parametrize(("law", "match"), [
    (th.FrictionLaw("cubic"), r"c.form: 'cubic'; allowed: exponential, linear, saturating, "
                              r"u_shaped"),
    (th.FrictionLaw("u_shaped", 0.6, 30.0), r"c.minimum_c must lie in \[45, 80\] °C"),
    (th.FrictionLaw("linear", 0.2), r"c.ratio_40c.*\[0.3, 1\]"),
    (th.FrictionLaw("linear", float("nan")), r"c.ratio_40c")])
def test_a_friction_law_out_of_range_is_refused_naming_the_key(law, match):
    with pytest.raises(ValueError, match=match):
        law.check("c")


# ------------------------------------------------------------ temperature sensor faults
def _faulty(fault: str, fault_hour: float, drift: float = 0.0, noise: float = 0.05,
            hours=None):
    true = np.linspace(20.0, 40.0, 11)
    h = np.arange(11.0) if hours is None else hours
    sensor = bd.TemperatureSensor(0.1, noise, fault, fault_hour, drift)
    good = bd.measure_temperature(true, bd.TemperatureSensor(0.1, noise),
                                  np.random.default_rng(7))
    return h, good, bd.measure_temperature(true, sensor, np.random.default_rng(7), hours=h)


def test_a_faultless_sensor_reads_bit_for_bit_as_before():
    true = np.linspace(18.0, 42.0, 1001)
    old = true + 0.05 * np.random.default_rng(5).standard_normal(true.shape)  # the old code
    old = np.round(old / 0.1) * 0.1
    new = bd.measure_temperature(true, bd.TemperatureSensor(), np.random.default_rng(5))
    assert np.array_equal(new, old)
    with_hours = bd.measure_temperature(true, bd.TemperatureSensor(fault_hour=3.0,
                                                                   drift_k_per_h=1.0),
                                        np.random.default_rng(5), hours=np.arange(1001.0))
    assert np.array_equal(with_hours, old)  # "none" ignores the fault's other fields


def test_a_stuck_sensor_holds_its_last_reading_before_the_fault_hour():
    h, good, r = _faulty("stuck", 5.5)
    assert np.array_equal(r[:6], good[:6])
    assert np.all(r[6:] == good[5]) and good[6:].std() > 1.0  # the joint warmed meanwhile
    for first in (0.0, -0.0, 2.0):  # at or before the first reading: the first one
        _, good, r = _faulty("stuck", first, hours=np.arange(11.0) + 2.0)
        assert np.all(r == good[0])


def test_a_drifting_sensor_gains_its_rate_times_the_hours_since_the_fault():
    h, good, r = _faulty("drift", 4.0, drift=0.3, noise=0.0)
    assert np.array_equal(r[:5], good[:5])
    np.testing.assert_allclose(r[4:] - good[4:], 0.3 * (h[4:] - 4.0), atol=0.05 + 1e-9)
    np.testing.assert_allclose(r * 10, np.round(r * 10), atol=1e-9)  # still quantised
    _, good, r = _faulty("drift", 0.0, drift=-0.5, noise=0.0)
    assert r[-1] - good[-1] == pytest.approx(-5.0, abs=0.05 + 1e-9)  # a loosened sensor


def test_a_dropped_out_sensor_reads_nan_from_the_fault_hour():
    h, good, r = _faulty("dropout", 3.0)
    assert np.array_equal(r[:3], good[:3]) and np.all(np.isnan(r[3:]))


@pytest.mark.parametrize(("sensor", "match"), [
    (bd.TemperatureSensor(fault="broken"),
     r"^c.fault: 'broken'; allowed: none, stuck, drift, dropout$"),
    (bd.TemperatureSensor(fault="stuck", fault_hour=-1.0), r"c.fault_hour must lie in \[0, inf"),
    (bd.TemperatureSensor(fault_hour=float("nan")), r"c.fault_hour must lie in \[0, inf"),
    (bd.TemperatureSensor(fault="drift", drift_k_per_h=float("inf")),
     r"c.drift_k_per_h must be a finite number")])
def test_a_sensor_fault_out_of_range_is_refused_naming_the_key(sensor, match):
    with pytest.raises(ValueError, match=match):
        sensor.check("c")


def test_a_faulty_sensor_needs_the_readings_hours():
    sensor = bd.TemperatureSensor(fault="dropout", fault_hour=1.0)
    with pytest.raises(ValueError, match=r"TemperatureSensor \(fault 'dropout', lag_min 0, "
                                         r"ageing_k_per_h 0\) needs the readings' operating "
                                         r"hours"):
        bd.measure_temperature([20.0, 21.0], sensor, np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"hours must be finite, of the readings' shape"):
        bd.measure_temperature([20.0, 21.0], sensor, np.random.default_rng(0), hours=[0.0])


def test_a_lagging_sensor_reads_behind_the_grease_on_a_warm_up():
    """Issue 83: the reading is its own node: a sensor 20 min behind the grease reads a
    step of the joint's temperature 63 % of the way after 20 min, 95 % after an hour
    (first order, exact for the held step); off, the readings are those of a sensor
    without the option, bit for bit, even with the hours given."""
    h = np.arange(180) / 60  # a reading a minute
    true = np.where(np.arange(180) < 60, 20.0, 40.0)  # 20 K more from the 61st reading on,
    lagged = bd.measure_temperature(  # held over the minute that ends at it
        true, bd.TemperatureSensor(0.0, 0.0, lag_min=20.0), np.random.default_rng(0), hours=h)
    for minutes, share in ((20, 1 - np.exp(-1.0)), (60, 1 - np.exp(-3.0))):
        assert lagged[59 + minutes] - 20.0 == pytest.approx(20.0 * share, rel=1e-9)
    assert np.all(lagged[:60] == 20.0) and np.all(np.diff(lagged) >= 0)
    off = bd.measure_temperature(true, bd.TemperatureSensor(), np.random.default_rng(3),
                                 hours=h)
    assert np.array_equal(off, bd.measure_temperature(true, bd.TemperatureSensor(),
                                                      np.random.default_rng(3)))


def test_a_sensors_offset_and_ageing_add_to_its_reading():
    h = np.linspace(0.0, 1000.0, 11)
    true = np.full(11, 30.0)
    r = bd.measure_temperature(true, bd.TemperatureSensor(0.0, 0.0, offset_k=0.4,
                                                          ageing_k_per_h=1e-3),
                               np.random.default_rng(0), hours=h)
    np.testing.assert_allclose(r, 30.4 + 1e-3 * h, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match=r"^c.lag_min must lie in \[0, 600\] min"):
        bd.TemperatureSensor(lag_min=-1.0).check("c")
    with pytest.raises(ValueError, match=r"^c.offset_k must be a finite number of K"):
        bd.TemperatureSensor(offset_k=float("nan")).check("c")


# ------------------------------------------------------------------- re-greasing
def test_regreasing_steps_the_friction_up_by_drop_and_it_runs_in_with_tau():
    h = np.array([0.0, 9.99, 10.0, 18.0, 34.0, 50.0, 60.0, 68.0])
    f = th.regrease_factor(h, [10.0, 60.0], 0.3, 8.0)
    np.testing.assert_allclose(f[:2], 1.0)  # before the first: as settled
    assert f[2] == pytest.approx(1.3) and f[6] == pytest.approx(1.3)  # each steps up by drop
    assert f[3] == pytest.approx(1.0 + 0.3 / np.e) and f[7] == pytest.approx(1.0 + 0.3 / np.e)
    assert f[4] == pytest.approx(1.0 + 0.3 * np.exp(-3.0))  # run in again within a day
    assert th.regrease_factor(30.0, [10.0], tau_h=th.REGREASE_TAU_H) < 1.1
    assert th.regrease_factor(10.0, [10.0]) == pytest.approx(1.0 + th.REGREASE_DROP)


@pytest.mark.parametrize(("kw", "match"), [
    ({"at_h": [10.0, 5.0]}, "at_h must be increasing"),
    ({"at_h": [-1.0]}, "at_h"),
    ({"drop": 1.5}, r"drop.*\[0, 1\]"),
    ({"tau_h": 0.0}, "tau_h")])
def test_regreasing_out_of_range_is_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        th.regrease_factor([1.0, 2.0], **{"at_h": [1.0], **kw})


# ---------------------------------------------------------- a measured warm-up
def test_a_traced_temperature_restarts_the_measured_rise_after_every_cold_start():
    trace_h, rise = np.array([0.0, 0.5, 1.0]), np.array([0.0, 4.0, 6.0])
    cfg = th.JointThermal(ambient_swing_k=0.0, run_h_per_day=16.0)
    h = np.array([0.0, 0.25, 1.0, 5.0, 15.99, 16.0, 16.5, 20.0])
    t = th.traced_temperature(h, trace_h, rise, cfg, scale=2.0)
    np.testing.assert_allclose(t, [20.0, 24.0, 32.0, 32.0, 32.0, 20.0, 28.0, 32.0])
    flat = th.JointThermal(ambient_swing_k=0.0, run_h_per_day=24.0)  # one start, at hour 0
    np.testing.assert_allclose(th.traced_temperature([0.5, 30.0], trace_h, rise, flat),
                               [24.0, 26.0])
    swing = th.JointThermal()  # the rise rides on the hall's swing
    np.testing.assert_allclose(th.traced_temperature(h, trace_h, rise, swing) -
                               th.ambient_temperature(th.wall_clock_h(h, 16.0), swing),
                               np.interp(h % 16.0, trace_h, rise), atol=1e-12)
    with pytest.raises(ValueError, match="trace_h, rise_k must share a shape"):
        th.traced_temperature(h, [0.5, 1.0], [0.0, 1.0], cfg)
    with pytest.raises(ValueError, match="scale"):
        th.traced_temperature(h, trace_h, rise, cfg, scale=-1.0)


# ---------------------------------------------------------------- named joints
#: The UR3 day's six fitted time constants, J0..J5 [min] (docs/calibration.md's table).
UR3_TAU_MIN = [45.9, 40.3, 37.8, 33.1, 32.1, 33.1]


def test_the_industrial_joint_is_the_default_and_the_small_cobot_the_ur3s_median_tau():
    assert th.JointThermal.preset("industrial") == th.JointThermal()
    cobot = th.JointThermal.preset("small_cobot")
    assert cobot.tau_min == pytest.approx(float(np.median(UR3_TAU_MIN)), abs=1e-12)
    assert min(UR3_TAU_MIN) <= cobot.tau_min <= max(UR3_TAU_MIN)
    # only tau was identified: every other field the default's
    assert dataclasses.replace(cobot, tau_min=th.JointThermal().tau_min) == th.JointThermal()
    assert th.JointThermal.preset("small_cobot", ambient_c=25.0).ambient_c == 25.0
    cobot.check()


def test_an_unknown_joint_is_refused_naming_the_allowed_ones():
    with pytest.raises(ValueError, match=r"^thermal preset must be one of industrial, "
                                         r"small_cobot, got 'kuka'$"):
        th.JointThermal.preset("kuka")
