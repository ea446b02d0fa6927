"""Influence functionals: every gauge signal as a small linear map of the loads.

For a truss model and a sensor layout, the five bridge signals are (module
:mod:`swgsim.gear.flexspline`)

    s(t) = w0 (A cos 2ψ + B sin 2ψ) + e (E_x cos θ_e + E_y sin θ_e) + T(t) h(ψ(t)),

with ψ the wave-generator angle relative to the flexspline, w0 the radial deflection, e
and θ_e an eccentricity, T the acting output torque and

    h(ψ) = Σ_i c_i g_i λ_i(ψ) / Σ_i c_i λ_i(ψ),   λ_i(ψ) = l_A w(θ_i − ψ) + l_B w(θ_i − ψ − π),

the tooth-load influence g_i (signal per unit torque carried at angle θ_i), the contact
window w of the two mesh zones around the major axis, their load shares l_A, l_B and the
tooth-force factors c_i (a tip crack sets c_i = 1 − severity at one angle).

One sparse factorisation of K_FF per structure and one adjoint solve per signal give
A, B, E_x, E_y and g. A root-tooth crack changes the stiffness of a few bars,
ΔK = U D Uᵀ; the Woodbury identity updates the adjoint solutions,
λ' = λ − Z (D⁻¹ + Uᵀ Z)⁻¹ Uᵀ λ with Z = K⁻¹ U, reusing the healthy factorisation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.gear.faults import angle_index, mesh_severity
from swgsim.gear.flexspline import TrussModel
from swgsim.gear.sensors import SensorLayout, signal_rows

sp = lazy_module("scipy.sparse")


@dataclass(frozen=True)
class Influence:
    """Influence coefficients of the five signals.

    Attributes
    ----------
    A, B : ndarray, shape (5,)
        Signal per metre of WG deflection for cos 2ψ and sin 2ψ [mV/V / m].
    Ex, Ey : ndarray, shape (5,)
        Signal per metre of WG eccentricity along x and y of the flexspline [mV/V / m].
    g : ndarray, shape (5, n_theta)
        Signal per N m of output torque carried at angle θ_i [mV/V / N m].
    theta : ndarray, shape (n_theta,)
        Node angles [rad].
    """

    A: np.ndarray
    B: np.ndarray
    Ex: np.ndarray
    Ey: np.ndarray
    g: np.ndarray
    theta: np.ndarray


class InfluenceSolver:
    """Healthy factorisation and adjoint solutions of one truss; crack variants by Woodbury.

    Parameters
    ----------
    model : TrussModel
    alpha_tooth_rad : float
        Pressure angle of the teeth [rad] (radial share of the tooth force).
    """

    def __init__(self, model: TrussModel, alpha_tooth_rad: float = np.deg2rad(20.0)):
        self.model = model
        self.alpha = alpha_tooth_rad
        m = model
        self._F = m.free
        self._P = m.prescribed
        self._wg_pos = np.searchsorted(self._P, m.wg_dofs)  # wg dofs within P
        self._tooth = m.unit_tooth_loads(alpha_tooth_rad).tocsr()[self._F]  # (n_F, n_theta)
        self._K_PF = m.K[self._P][:, self._F].tocsr()
        n_rim = m.rim_stations.size
        th = np.tile(m.theta, n_rim)
        self._wg_basis = np.stack([np.cos(2 * th), np.sin(2 * th), np.cos(th), np.sin(th)])
        self._crack_cache: dict[int, tuple] = {}

    def coefficients(self, rows, lam) -> Influence:
        """Influence coefficients from signal rows (5, n_dof) and adjoints (n_F, 5)."""
        c_p = rows[:, self._P].toarray()  # (5, n_P)
        g_p = c_p - (self._K_PF @ lam).T  # (5, n_P)
        g_wg = g_p[:, self._wg_pos]  # (5, n_wg)
        A, B, Ex, Ey = (g_wg @ b for b in self._wg_basis)
        g = (self._tooth.T @ lam).T  # (5, n_theta)
        return Influence(A=A, B=B, Ex=Ex, Ey=Ey, g=np.asarray(g), theta=self.model.theta)

    def adjoint(self, layout: SensorLayout):
        """Signal rows (5, n_dof) and healthy adjoint solutions λ (n_F, 5)."""
        rows = signal_rows(self.model, layout)
        c_f = rows[:, self._F].toarray().T  # (n_F, 5)
        lam = self.model.lu.solve(c_f)
        return rows, lam

    def healthy(self, layout: SensorLayout) -> Influence:
        """Influence of the healthy structure for a sensor layout."""
        rows, lam = self.adjoint(layout)
        return self.coefficients(rows, lam)

    def _rotation(self, steps: int) -> np.ndarray:
        """Positions in F of the free DOFs rotated by ``steps`` node spacings.

        The truss, its supports and its loads are cyclically symmetric, and DOFs are
        cylindrical components, so a rotation by whole node spacings is a permutation:
        entry p is the position in F of the DOF that F[p] moves to.
        """
        m = self.model
        n_t = m.mesh.n_theta
        node, comp = np.divmod(self._F, 3)
        q, ang = np.divmod(node, n_t)
        moved = 3 * (q * n_t + (ang + steps) % n_t) + comp
        pos = np.full(m.n_dof, -1)
        pos[self._F] = np.arange(self._F.size)
        out = pos[moved]
        if np.any(out < 0):  # not expected: supports are axisymmetric
            raise RuntimeError("free DOF set is not cyclically symmetric")
        return out

    def _crack_basis(self, theta_index: int):
        """Reduced Woodbury data of the crack bars at an angle index.

        ΔK = U D Uᵀ with U = Bᵀ of the crack bars (all DOFs) and D = −s diag(k). Returns
        U_Fᵀ (r, n_F, sparse), the permutation of F that rotates index 0 onto this index,
        U_P[wg] (n_wg, r), k (r,), U_FᵀZ (r, r), (K_PF Z)[wg] (n_wg, r) and
        toothᵀZ (n_theta, r), with Z = K_FF⁻¹ U_F: all that an updated influence needs.

        Only the crack at index 0 is solved for (r sparse solves); every other position
        is its rotation (cyclic symmetry, :meth:`_rotation`), exact to round-off.
        """
        if 0 not in self._crack_cache:
            bars = self.model.root_crack_bars(0)
            rows = self.model.bar_rows(bars)  # (r, n_dof), sparse
            u_f = rows[:, self._F].tocsr()  # U_Fᵀ
            u_p_wg = rows[:, self._P][:, self._wg_pos].toarray().T  # (n_wg, r)
            dense = u_f.toarray()
            # column by column: SuperLU's multi-RHS solve is slower here (measured)
            Z = np.column_stack([self.model.lu.solve(dense[k]) for k in range(dense.shape[0])])
            Z[np.abs(Z) < 1e-200] = 0.0  # flush subnormals: they make BLAS crawl
            self._crack_cache[0] = (u_f, np.arange(self._F.size), u_p_wg,
                                    self.model.k_bar[bars], np.asarray(u_f @ Z),
                                    (self._K_PF @ Z)[self._wg_pos],
                                    np.asarray(self._tooth.T @ Z))
        i = int(theta_index) % self.model.mesh.n_theta
        if i not in self._crack_cache:
            u_f, _, u_p_wg, k_c, utz, kpz_wg, tz = self._crack_cache[0]
            n_t = self.model.mesh.n_theta

            def roll(a):  # rows ordered (rim station, angle): shift the angle by i
                return np.roll(a.reshape(-1, n_t, a.shape[-1]), i, axis=1).reshape(a.shape)

            self._crack_cache[i] = (u_f, self._rotation(i), roll(u_p_wg), k_c, utz,
                                    roll(kpz_wg), np.roll(tz, i, axis=0))
        return self._crack_cache[i]

    def root_crack_at(self, layout: SensorLayout, position_deg: float, severity: float,
                      adjoint=None, healthy: Influence | None = None) -> Influence:
        """Influence with a root crack at a position [deg] of nominal severity.

        The crack cuts the bars after the node nearest to ``position_deg``; the nominal
        severity (defined on the reference mesh) is converted to this mesh with
        :func:`swgsim.gear.faults.mesh_severity` so that the crack's compliance does not depend
        on the mesh.
        """
        n = self.model.mesh.n_theta
        return self.root_crack(layout, angle_index(position_deg, n),
                               mesh_severity(severity, n), adjoint=adjoint, healthy=healthy)

    def root_crack(self, layout: SensorLayout, theta_index: int, severity: float,
                   adjoint=None, healthy: Influence | None = None) -> Influence:
        """Influence with a root-tooth crack (bars scaled by 1 − severity), by Woodbury.

        Parameters
        ----------
        layout : SensorLayout
        theta_index : int
            Angle index of the cracked tooth root.
        severity : float
            Fraction of bar stiffness lost, 0 <= severity < 1.
        adjoint : tuple, optional
            Precomputed ``adjoint(layout)`` to reuse.
        healthy : Influence, optional
            Precomputed healthy influence of the same layout to reuse.

        Raises
        ------
        ValueError
            If severity is outside [0, 1).
        """
        if not 0.0 <= severity < 1.0:
            raise ValueError(f"root-crack severity must lie in [0, 1), got {severity}")
        rows, lam = adjoint if adjoint is not None else self.adjoint(layout)
        if severity == 0.0:
            return self.coefficients(rows, lam)
        u_ft, perm, u_p_wg, k_c, utz, kpz_wg, tz = self._crack_basis(theta_index)
        d = -severity * k_c
        S = np.diag(1.0 / d) + utz  # (r, r)
        ul = np.asarray(u_ft @ lam[perm])  # U_Fᵀ λ of the rotated crack, (r, 5)
        y = np.linalg.solve(S, ul)  # λ' = λ − Z y
        h = healthy if healthy is not None else self.coefficients(rows, lam)
        # G_P' = c_P − K'_PF λ' with K'_PF = K_PF + U_P D U_Fᵀ:
        #      = G_P + K_PF Z y − U_P D U_Fᵀ λ',  U_Fᵀ λ' = U_Fᵀ λ − U_FᵀZ y
        g_wg_delta = (kpz_wg @ y - u_p_wg @ (d[:, None] * (ul - utz @ y))).T
        A, B, Ex, Ey = (g_wg_delta @ b for b in self._wg_basis)
        return Influence(A=h.A + A, B=h.B + B, Ex=h.Ex + Ex, Ey=h.Ey + Ey,
                         g=h.g - (tz @ y).T, theta=h.theta)


def contact_window(delta: np.ndarray, half_width_rad: float) -> np.ndarray:
    """Load distribution over one mesh zone, cos² of the angle from the major axis.

    Parameters
    ----------
    delta : ndarray
        Angle from the major axis [rad] (any range; wrapped to (−π, π]).
    half_width_rad : float
        Half-width of the zone in mesh [rad] (20 deg default [unverified]: about 10 % of
        the teeth carry load at rated torque, a common figure for SWGs).
    """
    d = np.mod(delta + np.pi, 2 * np.pi) - np.pi
    c = np.cos((0.5 * np.pi / half_width_rad) * d)
    return np.where(np.abs(d) < half_width_rad, c * c, 0.0)


def torque_influence(psi: np.ndarray, g: np.ndarray, theta: np.ndarray, c: np.ndarray,
                     half_width_rad: float, share_a: np.ndarray | float = 1.0) -> np.ndarray:
    """h(ψ): signal per unit output torque of two mesh zones, exact and fast.

    Only nodes within the zone half-width carry load, so each zone is summed over the
    2K + 1 nodes nearest its centre (K = ceil(half-width / Δθ) + 1) instead of all nodes:
    the same sum as over all nodes (tested against one truss solve per angle with every
    node's weight, ``tests/swgsim/test_flexspline.py``), at O(n_t K) cost.

    Parameters
    ----------
    psi : ndarray, shape (n_t,)
        WG angle relative to the flexspline [rad].
    g : ndarray, shape (5, n_theta)
        Signal per unit torque carried at each node angle [mV/V / N m].
    theta : ndarray, shape (n_theta,)
        Node angles, uniformly spaced from 0 [rad].
    c : ndarray, shape (n_theta,)
        Tooth-force factors (1 healthy; 1 − severity at a tip crack).
    half_width_rad : float
        Half-width of a mesh zone [rad].
    share_a : float or ndarray, shape (n_t,)
        Load factor of the zone at ψ; the zone at ψ + π carries 2 − share_a.

    Returns
    -------
    ndarray, shape (5, n_t)
    """
    n = theta.size
    dth = 2 * np.pi / n
    k = int(np.ceil(half_width_rad / dth)) + 1
    offs = np.arange(-k, k + 1)
    sa = np.broadcast_to(np.asarray(share_a, float), psi.shape)
    n_t = psi.size
    cols, vals = [], []
    alpha = 0.5 * np.pi / half_width_rad * dth  # window phase per node spacing
    ck, sk = np.cos(alpha * offs), np.sin(alpha * offs)
    for centre, share in ((psi, sa), (psi + np.pi, 2.0 - sa)):
        pos = centre / dth
        base = np.round(pos).astype(np.int64)
        frac = pos - base  # in [-0.5, 0.5]
        # cos(alpha (k - frac)) by the addition theorem: two trig calls per time step
        cw = np.cos(alpha * frac)[:, None] * ck + np.sin(alpha * frac)[:, None] * sk
        inside = np.abs(offs[None, :] - frac[:, None]) * dth < half_width_rad
        idx = (base[:, None] + offs[None, :]) % n  # (n_t, 2K+1)
        w = np.where(inside, cw * cw, 0.0) * c[idx] * share[:, None]
        cols.append(idx)
        vals.append(w)
    # one sparse row of zone weights per time step; the weighted sums are a CSR product
    idx = np.concatenate(cols, axis=1)
    w = np.concatenate(vals, axis=1)
    m = idx.shape[1]
    wmat = sp.csr_matrix((w.ravel(), idx.ravel(), np.arange(0, n_t * m + 1, m)),
                         shape=(n_t, n))
    num = wmat @ g.T  # (n_t, 5)
    return (num / w.sum(axis=1)[:, None]).T


@dataclass(frozen=True)
class ZoneTable:
    """One mesh zone's weighted sums tabulated on a uniform grid of the WG angle ψ.

    ``values[m]`` holds Σ_i w(θ_i − ψ_m) c_i g_i (five signals) and Σ_i w(θ_i − ψ_m) c_i
    at ψ_m = 2π m / M; row M repeats row 0 (periodic). The zone at ψ + π reads the same
    table at ψ + π, so :meth:`torque_influence` returns h(ψ) of :func:`torque_influence`
    by linear interpolation. Build with :func:`zone_table`.

    Attributes
    ----------
    values : ndarray, shape (M + 1, 6)
    """

    values: np.ndarray

    def torque_influence(self, psi: np.ndarray, share_a: np.ndarray | float = 1.0) -> np.ndarray:
        """h(ψ) by table look-up; same arguments and result as :func:`torque_influence`.

        Parameters
        ----------
        psi : ndarray, shape (n_t,)
            WG angle relative to the flexspline [rad].
        share_a : float or ndarray, shape (n_t,)
            Load factor of the zone at ψ; the zone at ψ + π carries 2 − share_a.

        Returns
        -------
        ndarray, shape (5, n_t)
        """
        psi = np.ascontiguousarray(psi, dtype=float)
        sa = np.ascontiguousarray(np.broadcast_to(np.asarray(share_a, float), psi.shape))
        out = np.empty((5, psi.size))
        _lookup(self.values, psi, sa, out)
        return out


@numba.njit(cache=True)
def _lookup(values, psi, share_a, out):
    """:meth:`ZoneTable.torque_influence` sample by sample, compiled: the two zones' rows
    interpolated linearly and added, the five signals divided by the weight (the same
    operations in the same order as on arrays, so the same numbers)."""
    m = values.shape[0] - 1
    scale = m / (2 * np.pi)
    acc = np.empty(6)
    for t in range(psi.size):
        for zone in range(2):
            centre = psi[t] if zone == 0 else psi[t] + np.pi
            share = share_a[t] if zone == 0 else 2.0 - share_a[t]
            u = np.mod(centre, 2 * np.pi) * scale
            i = min(int(u), m - 1)
            f = u - i
            for k in range(6):
                z = (values[i, k] * (1.0 - f) + values[i + 1, k] * f) * share
                acc[k] = z if zone == 0 else acc[k] + z
        for k in range(5):
            out[k, t] = acc[k] / acc[5]


#: Grid points per node spacing of :func:`zone_table`.
TABLE_SUBDIVISIONS = 64


def zone_table(g: np.ndarray, theta: np.ndarray, c: np.ndarray, half_width_rad: float,
               subdivisions: int = TABLE_SUBDIVISIONS) -> ZoneTable:
    """Tabulate one zone's sums for :meth:`ZoneTable.torque_influence`.

    Parameters
    ----------
    g : ndarray, shape (5, n_theta)
        Signal per unit torque carried at each node angle [mV/V / N m].
    theta : ndarray, shape (n_theta,)
        Node angles, uniformly spaced from 0 [rad].
    c : ndarray, shape (n_theta,)
        Tooth-force factors.
    half_width_rad : float
        Half-width of a mesh zone [rad].
    subdivisions : int, default 64
        Grid points per node spacing; linear interpolation then reproduces
        :func:`torque_influence` to about 5e-8 of the signal range (1e-8 at 128), tested.

    Returns
    -------
    ZoneTable
    """
    m = theta.size * int(subdivisions)
    grid = 2 * np.pi * np.arange(m) / m
    n = theta.size
    dth = 2 * np.pi / n
    k = int(np.ceil(half_width_rad / dth)) + 1
    idx = (np.round(grid / dth).astype(np.int64)[:, None] + np.arange(-k, k + 1)) % n  # (M, 2K+1)
    w = contact_window(theta[idx] - grid[:, None], half_width_rad) * c[idx]  # (M, 2K+1)
    vals = np.column_stack([(w[None] * g[:, idx]).sum(axis=-1).T, w.sum(axis=1)])  # (M, 6)
    return ZoneTable(np.vstack([vals, vals[:1]]))
