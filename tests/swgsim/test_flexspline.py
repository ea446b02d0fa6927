"""Space truss against closed forms (docs/PHYSICS.md sec. 3), mesh convergence, fast vs naive.

Tolerances are set at the accuracy reached, measured with the tests' own settings; each
states it (python -m pytest tests/swgsim/test_flexspline.py).
"""

from functools import lru_cache

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from physics_reference import cracked as crack_copy
from physics_reference import solve_displacements, wg_displacement

from swgsim.gear import influence as inf
from swgsim.gear.flexspline import INNER, FlexsplineGeometry, Mesh, TrussModel
from swgsim.gear.sensors import SensorLayout, face_strain_rows, signal_rows


def _tube(n_theta, length_m, rim_m, t_m=0.5e-3):
    geo = FlexsplineGeometry(r_collar_m=0.0, length_m=length_m, rim_width_m=rim_m,
                             t_rim_m=t_m, t_sleeve_m=t_m)
    return TrussModel(geo, Mesh(n_theta))


@lru_cache
def ring_bending_ratio(n_theta: int) -> float:
    """Outer-face circumferential strain of a free ring under w0 cos 2θ / closed form
    (t/2) 3 w0 / R² of a thin inextensional ring (docs/PHYSICS.md sec. 3); 6 mm wide, t = 0.5 mm.
    """
    m = _tube(n_theta, 6e-3, 6e-3)
    k = m.K.tocsc()
    j = np.arange(m.n_st)
    inner = m.node(j[:, None], INNER, np.arange(n_theta)[None, :]).ravel()
    w0 = 0.25e-3
    # radial displacement on every inner node; remove rigid rotation and axial shift only
    p = np.concatenate([3 * inner, [3 * m.node(0, INNER, 0) + 1],
                        3 * m.node(0, INNER, np.arange(n_theta)) + 2])
    up = np.concatenate([w0 * np.cos(2 * m.node_theta[inner]), [0.0], np.zeros(n_theta)])
    free = np.setdiff1d(np.arange(m.n_dof), p)
    u = np.zeros(m.n_dof)
    u[p] = up
    u[free] = spla.spsolve(k[free][:, free], -k[free][:, p] @ up)
    e = (face_strain_rows(m, [m.n_st // 2], [0.0], [0.0], [np.pi / 2], "outer") @ u)[0]
    ref = m.geometry.t_sleeve_m / 2 * 3 * w0 / m.geometry.r_mid_m**2  # (t/2) 3 w0 / R²
    return e / ref


def test_ring_bending_closed_form():
    """Default mesh (n_theta = 120, 1.3 mm cells on the 0.5 mm wall): reached +6.3 %,
    tolerance 7.5 % (+8.2 % against the wall-corrected form of the next test)."""
    assert ring_bending_ratio(120) == pytest.approx(1.0, abs=0.075)


def test_ring_bending_converges_at_second_order():
    """Richardson extrapolation over n_theta = 120, 240, 480 (from about 120 nodes on the
    crossing bars are no longer capped, so the meshes discretise one and the same wall).

    Observed order p = log2((r_120 − r_240) / (r_240 − r_480)); expected 2 (the lattice
    and the bilinear strain read-out of a smooth mode err by the squared cell size):
    reached 2.02, band [1.7, 2.3]. The extrapolated limit r_480 − (r_240 − r_480) /
    (2^p − 1) against the thin-ring form corrected for the wall [derived]: outer face at
    R + t/2 (factor R / (R + t/2), curved-beam strain) and transverse-shear compliance
    κ_s G t of a Timoshenko ring in mode n = 2 (factor 1 / (1 + E t² n² / (12 κ_s G R²))),
    together -1.75 %: limit -1.58 %, reached 0.17 %, tolerance 0.35 % (plate bending
    stiffness E t³ / 12(1 − ν²) instead of the beam's would put the form at -1.84 %).
    """
    r1, r2, r3 = (ring_bending_ratio(n) for n in (120, 240, 480))
    p = np.log2((r1 - r2) / (r2 - r3))
    assert 1.7 < p < 2.3
    limit = r3 - (r2 - r3) / (2**p - 1)
    geo = FlexsplineGeometry()
    big_r, t = geo.r_mid_m, geo.t_sleeve_m
    g = geo.e_pa / (2 * (1 + geo.nu))
    phi_shear = geo.e_pa * t**2 * 4 / (12 * geo.kappa_shear * g * big_r**2)
    closed = big_r / (big_r + t / 2) / (1 + phi_shear)
    assert limit == pytest.approx(closed, abs=0.0035)


@lru_cache
def torsion_shear_ratio(n_theta: int) -> float:
    """Outer-face shear strain of a tube under pure torque / closed form.

    Tube 30 mm long, t = 0.5 mm, torque carried by the rim nodes (3 mm), clamped at the
    other end; γ = ε(−45°) − ε(+45°) at mid-length on the outer face, against the thick
    tube's γ = T r_o / (G J), r_o = R + t/2, J = 2π R³ t (1 + t² / 4R²) (the thin-tube
    T / (2π R² t G) is 1.0 % lower).
    """
    m = _tube(n_theta, 30e-3, 3e-3)
    torque = 100.0
    f = np.asarray(m.unit_tooth_loads(0.0).sum(axis=1)).ravel() / m.mesh.n_theta * torque
    u = solve_displacements(m, f, np.zeros(m.prescribed.size))
    j = m.n_st // 2
    gam = ((face_strain_rows(m, [j], [0.5], [0.3], [-np.pi / 4], "outer")
            - face_strain_rows(m, [j], [0.5], [0.3], [np.pi / 4], "outer")) @ u)[0]
    geo = m.geometry
    g = geo.e_pa / (2 * (1 + geo.nu))
    big_r, t = geo.r_mid_m, geo.t_sleeve_m
    polar = 2 * np.pi * big_r**3 * t * (1 + t**2 / (4 * big_r**2))
    return gam / (torque * (big_r + t / 2) / (g * polar))


def test_torsion_shear_closed_form():
    """Default mesh (n_theta = 120): reached +0.078 %, tolerance 0.15 % (against the thin
    tube's closed form +1.09 %)."""
    assert torsion_shear_ratio(120) == pytest.approx(1.0, rel=1.5e-3)


def test_torsion_shear_converges_at_second_order():
    """Error against the closed form over n_theta = 40, 80, 160: +0.76 %, +0.18 %,
    +0.045 %; observed order log2(e_40 / e_160) / 2, expected 2 (as for the ring): reached
    2.04, band [1.7, 2.3]. (60, 120, 240 give 1.97, at 1.5x the time.)"""
    e = [torsion_shear_ratio(n) - 1 for n in (40, 80, 160)]
    assert all(x > 0 for x in e)
    p = np.log2(e[0] / e[2]) / 2
    assert 1.7 < p < 2.3


@pytest.fixture(scope="module")
def solver():
    return inf.InfluenceSolver(TrussModel(mesh=Mesh(120)))


def test_collar_shear_closed_form(solver):
    """Half bridge s2 on the collar: GF/4 · τ / G with τ = T / (2π r² t_c)."""
    lay = SensorLayout()
    h = solver.healthy(lay)
    geo = solver.model.geometry
    g = geo.e_pa / (2 * (1 + geo.nu))
    r = lay.signals[2].grids[0].r_m
    gamma = 1.0 / (2 * np.pi * r**2 * geo.t_collar_m * g)
    # reached 0.105 %, tolerance 0.2 %
    assert h.g[2].mean() == pytest.approx(1e3 * lay.gauge_factor / 4 * gamma, rel=2e-3)


def _naive_signals(solver, lay, psi, torque, w0, model=None, c=None):
    m = model or solver.model
    rows = signal_rows(solver.model, lay)
    hw = np.deg2rad(20.0)
    theta = m.theta
    c = np.ones(theta.size) if c is None else c
    w = (inf.contact_window(theta[None, :] - psi[:, None], hw)
         + inf.contact_window(theta[None, :] - psi[:, None] - np.pi, hw)) * c
    f = (m.unit_tooth_loads(solver.alpha) @ (w / w.sum(1, keepdims=True)).T) * torque
    up = np.zeros((m.prescribed.size, psi.size))
    up[np.searchsorted(m.prescribed, m.wg_dofs)] = wg_displacement(m, psi, w0).T
    return rows @ solve_displacements(m, np.asarray(f), up)


def _fast_signals(i, psi, torque, w0, c=None):
    c = np.ones(i.theta.size) if c is None else c
    h = inf.torque_influence(psi, i.g, i.theta, c, np.deg2rad(20.0))
    return w0 * (i.A[:, None] * np.cos(2 * psi) + i.B[:, None] * np.sin(2 * psi)) + torque * h


def test_influence_matches_naive_solver(solver):
    lay = SensorLayout()
    psi = np.array([0.1, 0.7, 2.0, 4.0])
    torque = np.array([70.0, 50.0, 10.0, 0.0])
    naive = _naive_signals(solver, lay, psi, torque, 0.254e-3)
    fast = _fast_signals(solver.healthy(lay), psi, torque, 0.254e-3)
    assert np.abs(fast - naive).max() <= 1e-9 * np.abs(naive).max()


@pytest.mark.parametrize("crack, tol", [(0.0, 5e-8), (0.8, 2e-7)])
def test_zone_table_matches_the_direct_sum(solver, crack, tol):
    """The tabulated torque influence (compiled look-up, both zones, eccentric load share)
    against the direct sum over the nodes: within 5e-8 of the signal range on a healthy
    gear (64 grid points per node spacing; measured 4.1e-8), within 2e-7 with a tip
    crack's sharp step in the tooth factors (measured 1.1e-7)."""
    i = solver.healthy(SensorLayout())
    c = 1.0 - crack * (np.abs(np.angle(np.exp(1j * (i.theta - 1.0)))) < 0.05)
    hw = np.deg2rad(20.0)
    psi = np.random.default_rng(3).uniform(-40.0, 40.0, 2000)
    share = 1.0 + 0.05 * np.cos(psi - 0.4)
    direct = inf.torque_influence(psi, i.g, i.theta, c, hw, share)
    table = inf.zone_table(i.g, i.theta, c, hw).torque_influence(psi, share)
    assert 0 < np.abs(table - direct).max() <= tol * np.ptp(direct)


def test_woodbury_root_crack_matches_refactorised_solver(solver):
    lay = SensorLayout()
    psi = np.array([0.05, 0.1, 0.15, 3.2])
    torque = np.full(4, 39.0)
    cracked = crack_copy(solver.model, 3, 0.9)
    # naive: a fresh factorisation of the cracked structure
    cracked_lu = spla.splu(cracked.K[solver.model.free][:, solver.model.free].tocsc())
    rows = signal_rows(solver.model, lay)
    hw = np.deg2rad(20.0)
    th = solver.model.theta
    w = inf.contact_window(th[None, :] - psi[:, None], hw) + inf.contact_window(
        th[None, :] - psi[:, None] - np.pi, hw)
    f = (cracked.unit_tooth_loads(solver.alpha) @ (w / w.sum(1, keepdims=True)).T) * torque
    up = np.zeros((cracked.prescribed.size, psi.size))
    up[np.searchsorted(cracked.prescribed, cracked.wg_dofs)] = wg_displacement(
        cracked, psi, 0.254e-3).T
    k_fp = cracked.K[cracked.free][:, cracked.prescribed]
    u = np.zeros((cracked.n_dof, psi.size))
    u[cracked.free] = cracked_lu.solve(np.asarray(f)[cracked.free] - k_fp @ up)
    u[cracked.prescribed] = up
    naive = rows @ u
    fast = _fast_signals(solver.root_crack(lay, 3, 0.9), psi, torque, 0.254e-3)
    assert np.abs(fast - naive).max() <= 1e-9 * np.abs(naive).max()
    healthy = _fast_signals(solver.healthy(lay), psi, torque, 0.254e-3)
    assert np.abs(fast - healthy).max() > 1e-6  # the crack is visible at all


def test_bad_mesh_and_gauge_are_refused():
    with pytest.raises(ValueError, match="multiple of 20"):
        TrussModel(mesh=Mesh(50))
    from swgsim.gear.sensors import Grid, grid_row

    m = TrussModel(mesh=Mesh(120))
    with pytest.raises(ValueError, match="leaves the collar"):
        grid_row(m, Grid(60e-3, 0.0, 0.0))
    # 1.7 mm cells at r = 32 mm with n_theta = 120: a 1 mm grid would not average
    with pytest.raises(ValueError, match="too coarse for the gauge layout"):
        grid_row(m, Grid(32e-3, 0.0, 0.0, length_m=1e-3))


@pytest.mark.slow
def test_mesh_fidelity_default_vs_twice_as_fine():
    """The default truss (n_theta = 120) against n_theta = 240 (scripts/mesh_convergence.py):
    signals reached 3.5 % RMS, tolerance 4.5 %; fault signatures (faulty minus healthy)
    reached 6.9 %, tolerance 8.5 %."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scripts" / "mesh_convergence.py"
    spec = importlib.util.spec_from_file_location("mesh_convergence", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.main(["--meshes", "120", "240"])
    assert out[120]["overall"] < 0.045
    assert out[120]["fault_signature"] < 0.085
