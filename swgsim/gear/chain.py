"""The simulation chain (paper Fig. 2): dynamics -> flexspline -> strain gauges.

:class:`SimulationChain` holds one flexspline truss with its factorisation and produces
the five bridge signals of many gear variants at one operating point
(:meth:`SimulationChain.simulate`) or along an operating profile with its transients
(:meth:`SimulationChain.simulate_profile`, :mod:`swgsim.gear.profile`):

    s(t) = w0 (A cos 2ψ + B sin 2ψ) + e (E_x cos θ_e + E_y sin θ_e) + T_out(t) h(ψ(t)) + z,

(:mod:`swgsim.gear.influence`), with ψ = φ_in − φ_out, T_out from the dynamic model and z
the bridges' zero offsets of the gear's layout (:class:`swgsim.gear.sensors.Signal`).
An eccentric WG also shifts load between the two mesh zones: the zone whose engagement the
eccentricity deepens carries the share 1 + κ_e (e / w0) cos(ψ − θ_e) [unverified, κ_e = 1:
load share proportional to engagement depth]. The reference path, one sparse solve of
the whole truss per time step, is ``signals_naive`` in ``tests/physics_reference.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numba
import numpy as np

from swgsim.base.typed import check_range
from swgsim.gear import dynamics, profile_dynamics
from swgsim.gear.faults import ChainParams
from swgsim.gear.flexspline import FlexsplineGeometry, Mesh, TrussModel
from swgsim.gear.influence import (
    TABLE_SUBDIVISIONS,
    Influence,
    InfluenceSolver,
    ZoneTable,
    torque_influence,
    zone_table,
)
from swgsim.gear.profile import Profile
from swgsim.gear.sensors import SensorLayout

#: Zone tables a chain keeps (about 0.5-1 MB each), one per (root crack, tip crack) group.
MAX_TABLES = 32


@dataclass
class ChainSettings:
    """Numerical and mesh-contact settings of the chain.

    Attributes
    ----------
    sample_rate_hz : float
        Sample rate of the windows [Hz] (10 kHz: order 37 of 4000 rpm below Nyquist).
    window_s : float
        Window length [s] (0.12 s: 4 input revolutions at 2000 rpm, 8 at 4000 rpm, so the
        sub-harmonics of eq. (10) fit whole periods).
    settle_s : float
        Transient simulated and discarded before the window [s].
    substeps : int
        RK4 steps per sample.
    contact_half_width_deg : float
        Half-width of each mesh zone [deg] [unverified].
    ecc_load_share : float
        κ_e, load-share sensitivity to eccentricity [-] [unverified].
    """

    sample_rate_hz: float = 10e3
    window_s: float = 0.12
    settle_s: float = 0.05
    substeps: int = 1
    contact_half_width_deg: float = 20.0
    ecc_load_share: float = 1.0

    def check(self, where: str = "chain") -> None:
        """Refuse a setting outside its range, naming ``<where>.<key>``; the contact width
        and the eccentric load share are judged with the mesh and the faults by the data
        set (:meth:`swgsim.datasets.config.DatasetConfig.check`).

        Raises
        ------
        ValueError
            ``<where>.window_s must lie in (0, 10] s, got ...`` and the like.
        """
        check_range(self.sample_rate_hz, 0.0, 1e6, f"{where}.sample_rate_hz", "Hz", lo_open=True)
        check_range(self.window_s, 0.0, 10.0, f"{where}.window_s", "s", lo_open=True)
        check_range(self.settle_s, 0.0, 10.0, f"{where}.settle_s", "s")
        check_range(self.substeps, 1, 100, f"{where}.substeps")


class SimulationChain:
    """Dynamics, flexspline truss and gauges of one gear design.

    Parameters
    ----------
    layout : SensorLayout
        Gauge layout of this gear (with its tolerances).
    geometry : FlexsplineGeometry, optional
    mesh : Mesh, optional
    settings : ChainSettings, optional
    solver : InfluenceSolver, optional
        Share one factorised truss between several layouts (gears of one design).

    Raises
    ------
    ValueError
        If a gauge lies off the collar or the mesh is too coarse for the layout.
    """

    def __init__(self, layout: SensorLayout | None = None,
                 geometry: FlexsplineGeometry | None = None, mesh: Mesh | None = None,
                 settings: ChainSettings | None = None, solver: InfluenceSolver | None = None,
                 alpha_tooth_rad: float = np.deg2rad(20.0)):
        self.layout = layout or SensorLayout()
        # a copy: the chain owns its settings (a config changed later changes nothing here)
        self.settings = replace(settings) if settings is not None else ChainSettings()
        self._influence: dict[tuple | None, Influence] = {}
        self._tables: dict[tuple, ZoneTable] = {}
        if solver is None:
            solver = InfluenceSolver(TrussModel(geometry, mesh), alpha_tooth_rad)
        self.solver = solver
        self.model = solver.model
        self._rows_lam = solver.adjoint(self.layout)  # validates the layout early

    @classmethod
    def from_influences(cls, layout: SensorLayout, influences: dict[tuple | None, Influence],
                        settings: ChainSettings | None = None) -> SimulationChain:
        """A chain from precomputed influences, keyed by ``ChainParams.root_crack_key()``.

        The key :data:`~swgsim.gear.faults.NO_ROOT_CRACK` is the healthy structure. Such a chain
        needs no truss (workers of the generator get their influences from the parent
        process); variants whose root crack is not among the keys raise KeyError, and the
        naive reference path is not available.
        """
        chain = cls.__new__(cls)  # no truss in this process
        chain.layout = layout
        chain.settings = replace(settings) if settings is not None else ChainSettings()
        chain.solver = chain.model = chain._rows_lam = None
        chain._influence = dict(influences)
        chain._tables = {}
        return chain

    # ------------------------------------------------------------------ influence
    def influence(self, p: ChainParams) -> Influence:
        """Influence coefficients for a variant's flexspline (healthy or root crack)."""
        key = p.root_crack_key()
        if key not in self._influence:
            if self.solver is None:
                raise KeyError(f"no precomputed influence for root crack {key}")
            if not p.has_root_crack:
                inf = self.solver.coefficients(*self._rows_lam)
            else:
                inf = self.solver.root_crack_at(self.layout, p.root_crack_deg,
                                                p.root_crack_severity, adjoint=self._rows_lam)
            self._influence[key] = inf
        return self._influence[key]

    def _tooth_factors(self, p: ChainParams) -> np.ndarray:
        return p.tooth_factors(self.influence(p).theta)

    def load_share(self, p: ChainParams, psi: np.ndarray) -> np.ndarray:
        """Load factor of the mesh zone at ψ (the one at ψ + π carries 2 − it)."""
        if p.ecc_m == 0.0:
            return np.ones_like(psi)
        return 1.0 + self.settings.ecc_load_share * (p.ecc_m / p.w0_m) * np.cos(
            psi - p.ecc_theta_rad)

    # ------------------------------------------------------------------ signals
    def simulate(self, variants: list[ChainParams], n_in_rpm, t_out_nm,
                 phi_in0: np.ndarray | float = 0.0, friction_effects=None):
        """Simulate variants at one operating point.

        Parameters
        ----------
        variants : list of ChainParams
            V variants.
        n_in_rpm : float or ndarray, shape (V,)
            Desired input speed [rpm], > 0.
        t_out_nm : float or ndarray, shape (V,)
            Load torque [N m], >= 0.
        phi_in0 : float or ndarray, shape (V,)
            Input angle at t = 0 [rad].
        friction_effects : swgsim.gear.friction.simulation.FrictionEffects, optional
            Extra output friction accepted by a calibration (see
            :func:`swgsim.gear.dynamics.simulate`); None: the paper law alone.

        Returns
        -------
        signals : ndarray, shape (V, 5, n_t)
            [mV/V].
        result : dynamics.SimResult
        """
        st = self.settings
        res = dynamics.simulate([v.gear for v in variants], n_in_rpm, t_out_nm, phi_in0,
                                st.sample_rate_hz, st.window_s, st.settle_s, st.substeps,
                                friction_effects=friction_effects)
        if not res.success:
            raise RuntimeError(f"dynamic simulation failed: {res.message}")
        return self.signals_batch(variants, res.psi, res.t_out), res

    def simulate_profile(self, variants: list[ChainParams], profile: Profile,
                         phi_in0: np.ndarray | float = 0.0, duration_s: float | None = None,
                         feedforward: bool = False):
        """Simulate variants along an operating profile, recorded from t = 0.

        Runs :func:`swgsim.gear.profile_dynamics.simulate_profile` at the chain's sample rate and
        substeps and maps the recorded motion to the bridge signals with
        :meth:`signals_batch`: ψ = φ_in − φ_out from the states and the acting output
        torque t_out = c T_stiff − T_fric / sin α of the recorded states, the same
        quantity and sign as :meth:`simulate` (positive when the gear drives the load
        forward at positive speed). A reversed motion or an overhauling load gives a
        negative t_out; it passes through signed, since the flexspline's torque strain is
        linear in the torque (s = ... + t_out h(ψ)).

        Parameters
        ----------
        variants : list of ChainParams
            V variants.
        profile : swgsim.gear.profile.Profile
            Desired speed and load, the same for all variants.
        phi_in0 : float or ndarray, shape (V,)
            Input angle at t = 0 [rad].
        duration_s : float, optional
            Recorded length [s]; default the profile's duration.
        feedforward : bool
            Add the acceleration feed-forward torque to the motor torque.

        Returns
        -------
        signals : ndarray, shape (V, 5, n_t)
            s0..s4 [mV/V] at times ``result.time`` (from t = 0, transients included).
        result : profile_dynamics.ProfileResult

        Raises
        ------
        ValueError
            A profile beyond the catalogue limits or an unstable step
            (:func:`swgsim.gear.profile_dynamics.simulate_profile`).
        RuntimeError
            If the integration diverged (naming the profile).
        """
        st = self.settings
        res = profile_dynamics.simulate_profile([v.gear for v in variants], profile, phi_in0,
                                        st.sample_rate_hz, duration_s, st.substeps,
                                        feedforward)
        if not res.success:
            raise RuntimeError(f"dynamic simulation of profile {profile} failed: {res.message}")
        return self.signals_batch(variants, res.psi, res.t_out), res

    def _table(self, key: tuple, inf: Influence, c: np.ndarray, hw: float) -> ZoneTable:
        """The zone table of a group of variants (root crack, tip crack), kept for the
        chain's next calls (the :data:`MAX_TABLES` latest)."""
        if key not in self._tables:
            if len(self._tables) >= MAX_TABLES:
                del self._tables[next(iter(self._tables))]
            self._tables[key] = zone_table(inf.g, inf.theta, c, hw)
        return self._tables[key]

    def signals_batch(self, variants: list[ChainParams], psi: np.ndarray, t_out: np.ndarray,
                      chunk: int = 64) -> np.ndarray:
        """Signals of many variants from their motions (one variant at a time, the tests'
        reference: ``signals_from_motion`` in ``tests/physics_reference.py``).

        Variants that share a structure and tooth factors are evaluated together, in
        chunks of ``chunk`` windows, to keep Python overhead and temporaries small; their
        torque influence h(ψ) is read from one :class:`~swgsim.gear.influence.ZoneTable` when
        the group has more time steps than the table has points (within about 1e-8 mV/V
        of the direct sum at 70 N m, tested), else summed directly.

        Parameters
        ----------
        variants : list of ChainParams
            V variants.
        psi, t_out : ndarray, shape (V, n_t)
            WG angle relative to the flexspline [rad] and acting output torque [N m].

        Returns
        -------
        ndarray, shape (V, 5, n_t)
            s0..s4 [mV/V], the layout's zero offsets included.
        """
        v, n_t = psi.shape
        zero = self.layout.zero_offsets_mvv
        out = np.empty((v, 5, n_t))
        groups: dict[tuple, list[int]] = {}
        for k, p in enumerate(variants):
            tip = None if p.tip_crack_severity == 0.0 else (
                p.tip_crack_deg, p.tip_crack_severity, p.crack_width_deg)
            groups.setdefault((p.root_crack_key(), tip), []).append(k)
        hw = np.deg2rad(self.settings.contact_half_width_deg)
        for key, members in groups.items():
            p0 = variants[members[0]]
            inf = self.influence(p0)
            c = self._tooth_factors(p0)
            # a table pays when the group has more time steps than the table has points
            table = (self._table((*key, hw), inf, c, hw)
                     if len(members) * n_t > 2 * inf.theta.size * TABLE_SUBDIVISIONS else None)
            for start in range(0, len(members), chunk):
                idx = np.asarray(members[start:start + chunk])
                ps = psi[idx]  # (m, n_t)
                share = np.stack([self.load_share(variants[k], psi[k]) for k in idx])
                h = (torque_influence(ps.ravel(), inf.g, inf.theta, c, hw, share.ravel())
                     if table is None else table.torque_influence(ps.ravel(), share.ravel()))
                w0 = np.array([variants[k].w0_m for k in idx])
                ecc = np.array([[variants[k].ecc_m * np.cos(variants[k].ecc_theta_rad),
                                 variants[k].ecc_m * np.sin(variants[k].ecc_theta_rad)]
                                for k in idx])  # (m, 2)
                sig = np.empty((idx.size, 5, n_t))
                _compose(np.ascontiguousarray(ps), np.ascontiguousarray(t_out[idx]),
                         np.ascontiguousarray(h).reshape(5, idx.size, n_t), w0, inf.A, inf.B,
                         np.ascontiguousarray(ecc), inf.Ex, inf.Ey, zero, sig)
                out[idx] = sig
        return out


@numba.njit(cache=True)
def _compose(psi, t_out, h, w0, a, b, ecc, ex, ey, zero, out):
    """Signals of m variants (:meth:`SimulationChain.signals_batch`), sample by sample:
    w0 (A cos 2ψ + B sin 2ψ) + (e_x Ex + e_y Ey) + T_out h(ψ) + z, into ``out``
    (m, 5, n_t); the same operations in the same order as on arrays (z = 0 adds nothing:
    the bits of a chain without zero offsets)."""
    for i in range(psi.shape[0]):
        for t in range(psi.shape[1]):
            c, s = np.cos(2 * psi[i, t]), np.sin(2 * psi[i, t])
            for k in range(5):
                out[i, k, t] = (((w0[i] * (a[k] * c + b[k] * s)
                                  + (ecc[i, 0] * ex[k] + ecc[i, 1] * ey[k]))
                                 + t_out[i, t] * h[k, i, t]) + zero[k])
