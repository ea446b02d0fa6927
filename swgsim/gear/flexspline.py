"""Flexspline as a space truss (paper Sec. II-B, Fig. 5) and its influence functionals.

A hat-type flexspline (:class:`FlexsplineGeometry`, meshed by :class:`Mesh`) as two layers
of nodes joined by bars whose stiffnesses reproduce the wall's membrane, bending and
transverse-shear stiffness (lattice analogy, Hrennikoff 1941 / McHenry 1943); DOFs are
cylindrical, the collar clamped, the wave generator prescribing the inner rim's radial
displacement. :class:`TrussModel` assembles and factorises it once, so that every gauge
signal is a linear functional of the displacements (:mod:`swgsim.gear.influence`).
Geometry, bar stiffnesses, boundary conditions, validation: docs/PHYSICS.md sec. 3.1-3.6.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from swgsim.base.lazy import lazy_module

sp = lazy_module("scipy.sparse")

log = logging.getLogger(__name__)

INNER, OUTER = 0, 1


def factorize(k: sp.spmatrix):
    """Sparse LU of a symmetric positive definite stiffness matrix (SuperLU).

    Symmetric mode with minimum-degree ordering on Kᵀ + K and no pivoting: about 4x
    faster solves than the default COLAMD ordering on the flexspline (measured, 18k DOFs).
    """
    return sp.linalg.splu(sp.csc_matrix(k), permc_spec="MMD_AT_PLUS_A",
                     diag_pivot_thresh=0.0, options={"SymmetricMode": True})


@dataclass(frozen=True)
class FlexsplineGeometry:
    """Geometry and material of a hat-type flexspline, size 20, ratio 100.

    Attributes
    ----------
    r_mid_m : float
        Mid-wall radius of sleeve and rim [m]. Pitch radius 25.4 mm (catalogue, docs/PHYSICS.md
        sec. 2) less half the tooth height and half the wall [derived, 24.4 mm].
    rim_width_m : float
        Axial width of the toothed rim from the open end [m] (8 mm [unverified]).
    length_m : float
        Axial length from the open end to the collar [m] (18 mm [unverified]).
    r_collar_m : float
        Radius of the clamped collar edge [m] (38 mm [unverified]).
    t_rim_m, t_sleeve_m, t_collar_m : float
        Effective wall thickness of rim (teeth add stiffness), sleeve and collar [m]
        (0.8, 0.5, 0.6 mm [unverified]; the rim value reproduces the size-17 WG bending
        strain of about 2.8e-4 of docs/PHYSICS.md sec. 3 when scaled).
    e_pa : float
        Young's modulus [Pa], 206 GPa (steel; flexsplines are alloy steel).
    nu : float
        Poisson ratio of the lattice, fixed at 1/3 by the lattice analogy [-].
    kappa_shear : float
        Transverse shear stiffness of the wall relative to G t [-]. Small values keep the
        in-plane share of the crossing bars small; 0.05 gives under 5 % shear deflection
        for the order-2 ring mode (docs/PHYSICS.md sec. 3, derived).
    """

    r_mid_m: float = 24.4e-3
    rim_width_m: float = 8.0e-3
    length_m: float = 18.0e-3
    r_collar_m: float = 38.0e-3
    t_rim_m: float = 0.8e-3
    t_sleeve_m: float = 0.5e-3
    t_collar_m: float = 0.6e-3
    e_pa: float = 206e9
    nu: float = 1.0 / 3.0
    kappa_shear: float = 0.05


@dataclass
class Mesh:
    """Mesh density of the truss.

    Attributes
    ----------
    n_theta : int
        Nodes around the circumference per station and layer; a multiple of 20 so that the
        paper's twenty fault positions fall on nodes (Table V). Default 120 (3 deg).
    aspect : float
        Meridional station spacing relative to the circumferential spacing at the same
        radius (1 gives square cells; the lattice analogy needs 1/sqrt(3) < aspect < sqrt(3)).
    """

    n_theta: int = 120
    aspect: float = 1.0

    def check(self, where: str = "mesh") -> None:
        """Refuse a ``n_theta`` that is not a multiple of 20 in [20, 2000], naming
        ``<where>.n_theta``.

        Raises
        ------
        ValueError
            ``<where>.n_theta must be a multiple of 20 in [20, 2000], got ...``.
        """
        n = int(self.n_theta)
        if n % 20 or not 20 <= n <= 2000:
            raise ValueError(f"{where}.n_theta must be a multiple of 20 in [20, 2000], got "
                             f"{self.n_theta}")


def _meridian(geo: FlexsplineGeometry, mesh: Mesh):
    """Stations along the meridian: positions, normals, thickness, region flags.

    Returns
    -------
    dict of ndarray
        ``r``, ``z`` (n_st,) mid-surface position [m]; ``nr``, ``nz`` (n_st,) unit normal
        pointing to the outer layer (radially out on the sleeve, -z on the collar so that
        the outer wall continues into the collar's front face); ``t`` (n_st,) thickness
        [m]; ``rim`` (n_st,) bool; ``collar`` (n_st,) bool (stations with r > r_mid);
        ``clamped`` (n_st,) bool.
    """
    dth = 2 * np.pi / mesh.n_theta
    ds = geo.r_mid_m * dth * mesh.aspect
    n_sleeve = max(int(np.ceil(geo.length_m / ds)), 2)
    z_sl = np.linspace(0.0, geo.length_m, n_sleeve + 1)  # last one is the corner
    # collar: geometric spacing keeps cells square as the circumference grows;
    # r_collar_m <= r_mid_m gives a plain tube clamped at z = L (used in tests)
    if geo.r_collar_m > geo.r_mid_m:
        g = 1.0 + dth * mesh.aspect
        n_col = max(int(np.ceil(np.log(geo.r_collar_m / geo.r_mid_m) / np.log(g))), 2)
        r_col = geo.r_mid_m * (geo.r_collar_m / geo.r_mid_m) ** (np.arange(1, n_col + 1) / n_col)
    else:
        r_col = np.zeros(0)
    r = np.concatenate([np.full(z_sl.size, geo.r_mid_m), r_col])
    z = np.concatenate([z_sl, np.full(r_col.size, geo.length_m)])
    n_st = r.size
    nr = np.zeros(n_st)
    nz = np.zeros(n_st)
    nr[: z_sl.size] = 1.0
    nz[z_sl.size :] = -1.0
    k = z_sl.size - 1  # corner
    if r_col.size:
        nr[k], nz[k] = np.sqrt(0.5), -np.sqrt(0.5)
    rim = (z <= geo.rim_width_m + 1e-12) & (r <= geo.r_mid_m + 1e-12)
    t = np.where(rim, geo.t_rim_m, geo.t_sleeve_m)
    t[z_sl.size :] = geo.t_collar_m
    if r_col.size:
        t[k] = 0.5 * (geo.t_sleeve_m + geo.t_collar_m)
    collar = r > geo.r_mid_m + 1e-12
    clamped = np.zeros(n_st, bool)
    clamped[-1] = True
    return {"r": r, "z": z, "nr": nr, "nz": nz, "t": t, "rim": rim, "collar": collar,
            "clamped": clamped, "corner": k}


def _layer_offsets(geo: FlexsplineGeometry, mesh: Mesh, mer: dict) -> np.ndarray:
    """Layer separation h per station [m], matching bending stiffness (docs/PHYSICS.md sec. 3.3)."""
    t = mer["t"]
    # in-plane share of the crossing bars per unit width, relative to E t (square cell):
    # k_c a²/c² per layer edge with k_c = kappa G t b c² / (2 a h0²) (see _bars)
    h0 = t / np.sqrt(3.0)
    a = mer["r"] * 2 * np.pi / mesh.n_theta * mesh.aspect
    g = geo.e_pa / (2 * (1 + geo.nu))
    k_c = geo.kappa_shear * g * t * a**2 / (2 * h0**2)  # b ≈ a, c ≈ a
    c_edge = 9.0 / 8.0 * geo.e_pa * t / 2 * (2.0 / 3.0)  # edge share of C_xxxx t per layer
    c_diag = 9.0 / 8.0 * geo.e_pa * t / 2 * (1.0 / 3.0)
    c_layer = c_diag + c_edge - np.minimum(k_c, 0.5 * c_edge)
    # 2 c_layer (h/2)² = (9/8) E t³ / 12
    return np.sqrt(9.0 / 8.0 * geo.e_pa * t**3 / 12.0 / (2 * c_layer) * 4.0)


class TrussModel:
    """Space-truss flexspline: nodes, bars, stiffness, boundary conditions, solvers.

    Parameters
    ----------
    geometry : FlexsplineGeometry
    mesh : Mesh

    Attributes
    ----------
    nodes_m : ndarray, shape (3, n_nodes)
        Cartesian node positions [m]; node index ``(2 * j + layer) * n_theta + i`` for
        station j, layer 0 (inner) / 1 (outer), angle index i.
    theta : ndarray, shape (n_theta,)
        Node angles [rad].
    bars : ndarray, shape (2, n_bars)
        End nodes of each bar.
    k_bar : ndarray, shape (n_bars,)
        Axial stiffness EA/L of each bar [N/m].
    bar_kind : ndarray, shape (n_bars,)
        0 in-plane edge (meridional), 1 in-plane edge (circumferential), 2 in-plane
        diagonal, 3 through-thickness, 4 crossing (transverse shear).
    """

    def __init__(self, geometry: FlexsplineGeometry | None = None, mesh: Mesh | None = None):
        self.geometry = geometry or FlexsplineGeometry()
        # a copy: the model owns its mesh, so a config changed after the model was built
        # cannot change its node numbering
        self.mesh = dataclasses.replace(mesh) if mesh is not None else Mesh()
        if self.mesh.n_theta < 20 or self.mesh.n_theta % 20:
            raise ValueError(
                f"mesh.n_theta must be a multiple of 20 and >= 20, got {self.mesh.n_theta}"
            )
        if not (1 / np.sqrt(3) < self.mesh.aspect < np.sqrt(3)):
            raise ValueError(f"mesh.aspect must lie in (0.577, 1.732), got {self.mesh.aspect}")
        self.mer = _meridian(self.geometry, self.mesh)
        self.h = _layer_offsets(self.geometry, self.mesh, self.mer)
        n_t = self.mesh.n_theta
        self.theta = np.arange(n_t) * 2 * np.pi / n_t
        self.n_st = self.mer["r"].size
        self._build_nodes()
        self._build_bars()

    # ------------------------------------------------------------------ geometry
    def node(self, j, layer, i):
        """Node index of station j, layer (0 inner, 1 outer), angle index i (vectorised)."""
        return (2 * np.asarray(j) + np.asarray(layer)) * self.mesh.n_theta + np.asarray(i) % (
            self.mesh.n_theta
        )

    def _build_nodes(self):
        m = self.mer
        n_t = self.mesh.n_theta
        sign = np.array([-0.5, 0.5])
        # layer radius and z per (station, layer)
        rl = m["r"][:, None] + sign[None, :] * self.h[:, None] * m["nr"][:, None]
        zl = m["z"][:, None] + sign[None, :] * self.h[:, None] * m["nz"][:, None]
        self.layer_r = rl  # (n_st, 2)
        self.layer_z = zl
        r = np.repeat(rl.reshape(-1), n_t)
        z = np.repeat(zl.reshape(-1), n_t)
        th = np.tile(self.theta, 2 * self.n_st)
        self.node_theta = th
        self.nodes_m = np.stack([r * np.cos(th), r * np.sin(th), z])  # (3, n_nodes)
        self.n_nodes = self.nodes_m.shape[1]
        self.n_dof = 3 * self.n_nodes

    def _build_bars(self):
        geo, m, n_t = self.geometry, self.mer, self.mesh.n_theta
        e = geo.e_pa
        g = e / (2 * (1 + geo.nu))
        dth = 2 * np.pi / n_t
        i = np.arange(n_t)
        ends_a, ends_b, ks, kinds = [], [], [], []

        def add(na, nb, k, kind):
            na, nb = np.broadcast_arrays(np.asarray(na), np.asarray(nb))
            ends_a.append(na.ravel())
            ends_b.append(nb.ravel())
            ks.append(np.broadcast_to(k, na.shape).ravel().astype(float))
            kinds.append(np.full(na.size, kind))

        # per-station contributions accumulated on circumferential edges
        k_circ = np.zeros((self.n_st, 2))  # per layer
        k_circ_cross = np.zeros(self.n_st)
        for j in range(self.n_st - 1):
            a = np.hypot(m["r"][j + 1] - m["r"][j], m["z"][j + 1] - m["z"][j])
            rc = 0.5 * (m["r"][j] + m["r"][j + 1])
            b = rc * dth
            t = 0.5 * (m["t"][j] + m["t"][j + 1])
            h = 0.5 * (self.h[j] + self.h[j + 1])
            tl = t / 2
            d2 = a * a + b * b
            k_d = 3 * e * tl * d2 / (16 * a * b)
            k_a = 9 * e * tl * b / (8 * a) - 3 * e * tl * a / (8 * b)
            k_b = 9 * e * tl * a / (8 * b) - 3 * e * tl * b / (8 * a)
            # crossing bars (transverse shear kappa G t), per cell, both planes
            c2a = a * a + h * h
            kc_a = geo.kappa_shear * g * t * b * c2a / (2 * a * h * h)  # meridional plane
            c2b = b * b + h * h
            kc_b = geo.kappa_shear * g * t * a * c2b / (2 * b * h * h)  # circumferential
            # on coarse meshes cap them so that the edges keep at least half their
            # stiffness (the wall is then softer in transverse shear than kappa G t)
            kc_a = min(kc_a, 0.5 * k_a * c2a / (a * a))
            kc_b = min(kc_b, 0.5 * k_b * c2b / (b * b))
            # take their in-plane share off the edges (per layer)
            k_a_eff = k_a - kc_a * a * a / c2a
            k_b_eff = k_b - kc_b * b * b / c2b
            if min(k_a_eff, k_b_eff) <= 0:
                raise ValueError(
                    f"mesh too coarse or too distorted at station {j}: cell {a:.3g} x "
                    f"{b:.3g} m gives a non-positive edge stiffness; refine mesh.n_theta"
                )
            for layer in (INNER, OUTER):
                # meridional edges: half from each of the two cells sharing it -> each
                # meridional edge (j, i)-(j+1, i) gets k_a_eff/2 from cell i-1 and cell i
                add(self.node(j, layer, i), self.node(j + 1, layer, i), k_a_eff, 0)
                k_circ[j, layer] += k_b_eff / 2
                k_circ[j + 1, layer] += k_b_eff / 2
                add(self.node(j, layer, i), self.node(j + 1, layer, i + 1), k_d, 2)
                add(self.node(j, layer, i + 1), self.node(j + 1, layer, i), k_d, 2)
            # crossing bars in the meridional plane: pair per meridional edge, half from
            # each adjacent cell -> kc_a per pair position
            add(self.node(j, INNER, i), self.node(j + 1, OUTER, i), kc_a, 4)
            add(self.node(j, OUTER, i), self.node(j + 1, INNER, i), kc_a, 4)
            k_circ_cross[j] += kc_b / 2
            k_circ_cross[j + 1] += kc_b / 2
        for j in range(self.n_st):
            for layer in (INNER, OUTER):
                add(self.node(j, layer, i), self.node(j, layer, i + 1), k_circ[j, layer], 1)
            add(self.node(j, INNER, i), self.node(j, OUTER, i + 1), k_circ_cross[j], 4)
            add(self.node(j, OUTER, i), self.node(j, INNER, i + 1), k_circ_cross[j], 4)
            # through-thickness: tributary area of the node
            jm, jp = max(j - 1, 0), min(j + 1, self.n_st - 1)
            a_trib = 0.5 * np.hypot(m["r"][jp] - m["r"][jm], m["z"][jp] - m["z"][jm])
            area = a_trib * m["r"][j] * dth
            add(self.node(j, INNER, i), self.node(j, OUTER, i), e * area / self.h[j], 3)
        self.bars = np.stack([np.concatenate(ends_a), np.concatenate(ends_b)])
        self.k_bar = np.concatenate(ks)
        self.bar_kind = np.concatenate(kinds)

    # ------------------------------------------------------------------ stiffness
    def bar_rows(self, bar_idx=None):
        """Rows mapping nodal DOFs (cylindrical components) to bar elongations.

        Returns
        -------
        scipy.sparse.csr_matrix, shape (n_bars_sel, n_dof)
        """
        bars = self.bars if bar_idx is None else self.bars[:, bar_idx]
        xa, xb = self.nodes_m[:, bars[0]], self.nodes_m[:, bars[1]]
        d = xb - xa
        length = np.linalg.norm(d, axis=0)
        e = d / length  # (3, nb)
        nb = bars.shape[1]
        rows, cols, vals = [], [], []
        for end, sgn in ((0, -1.0), (1, 1.0)):
            th = self.node_theta[bars[end]]
            c, s = np.cos(th), np.sin(th)
            # u_cart = Q [u_r, u_t, u_z]; e·Q gives coefficients of the cylindrical DOFs
            coef = np.stack([e[0] * c + e[1] * s, -e[0] * s + e[1] * c, e[2]])  # (3, nb)
            for comp in range(3):
                rows.append(np.arange(nb))
                cols.append(3 * bars[end] + comp)
                vals.append(sgn * coef[comp])
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(nb, self.n_dof),
        )

    @cached_property
    def B(self) -> sp.csr_matrix:
        """Compatibility matrix, shape (n_bars, n_dof): bar elongations = B @ u."""
        return self.bar_rows()

    @cached_property
    def K(self) -> sp.csc_matrix:
        """Global stiffness matrix, shape (n_dof, n_dof) [N/m]: K = Bᵀ diag(k) B."""
        return (self.B.T @ sp.diags(self.k_bar) @ self.B).tocsc()

    # ------------------------------------------------------------------ DOF sets
    def dof(self, nodes, comp):
        """DOF index of component ``comp`` (0 r, 1 theta, 2 z) of ``nodes``."""
        return 3 * np.asarray(nodes) + comp

    @cached_property
    def rim_stations(self) -> np.ndarray:
        """Indices of the stations of the toothed rim."""
        return np.flatnonzero(self.mer["rim"])

    @cached_property
    def wg_dofs(self) -> np.ndarray:
        """Radial DOFs of the inner rim nodes, shape (n_rim_st * n_theta,), angle fastest."""
        j = self.rim_stations
        nodes = self.node(j[:, None], INNER, np.arange(self.mesh.n_theta)[None, :])
        return self.dof(nodes.ravel(), 0)

    @cached_property
    def clamped_dofs(self) -> np.ndarray:
        """All DOFs of the clamped collar edge (both layers)."""
        j = np.flatnonzero(self.mer["clamped"])
        nodes = self.node(j[:, None, None], np.arange(2)[None, :, None],
                          np.arange(self.mesh.n_theta)[None, None, :]).ravel()
        return np.concatenate([self.dof(nodes, c) for c in range(3)])

    @cached_property
    def prescribed(self) -> np.ndarray:
        """Prescribed DOFs P (sorted): clamped edge and wave-generator contact."""
        return np.unique(np.concatenate([self.clamped_dofs, self.wg_dofs]))

    @cached_property
    def free(self) -> np.ndarray:
        """Free DOFs F (sorted)."""
        mask = np.ones(self.n_dof, bool)
        mask[self.prescribed] = False
        return np.flatnonzero(mask)

    @cached_property
    def K_FF(self) -> sp.csc_matrix:
        """Stiffness restricted to the free DOFs."""
        return self.K[self.free][:, self.free].tocsc()

    @cached_property
    def lu(self):
        """Sparse LU factorisation of K_FF (scipy SuperLU), computed once."""
        log.debug("factorising K_FF (%d free DOFs)", self.free.size)
        return factorize(self.K_FF)

    # ------------------------------------------------------------------ loads
    def unit_tooth_loads(self, alpha_tooth_rad: float) -> sp.csr_matrix:
        """Nodal forces of a unit output torque carried at each angle index.

        Column i distributes 1 N m over the outer-layer rim nodes at angle θ_i (equal
        share per rim station): tangential force 1/(n_rim r) and radial force
        −tan(α) times that (pressure-angle component pointing inwards).

        Returns
        -------
        scipy.sparse.csr_matrix, shape (n_dof, n_theta)
        """
        n_t = self.mesh.n_theta
        j = self.rim_stations
        rows, cols, vals = [], [], []
        for jj in j:
            nodes = self.node(jj, OUTER, np.arange(n_t))
            r = self.layer_r[jj, OUTER]
            ft = 1.0 / (j.size * r)
            rows += [self.dof(nodes, 1), self.dof(nodes, 0)]
            cols += [np.arange(n_t)] * 2
            vals += [np.full(n_t, ft), np.full(n_t, -np.tan(alpha_tooth_rad) * ft)]
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.n_dof, n_t),
        )

    def root_crack_bars(self, theta_index: int) -> np.ndarray:
        """Bars cut by a root tooth crack between the nodes at θ_i and θ_{i+1}.

        A crack through the rim wall along the face width (paper Sec. II-B: the bar
        stiffness between neighbouring nodes in circumferential direction is reduced
        drastically at one tooth): every bar of the toothed rim that crosses the line
        between angle indices i and i + 1 — circumferential edges and in-plane diagonals of
        both layers and the crossing bars between the layers.
        """
        n_t = self.mesh.n_theta
        i0 = theta_index % n_t
        st, _, ang = self.node_station_layer_angle(self.bars)
        rim = self.mer["rim"][st].all(axis=0)
        crosses = ((ang[0] == i0) & (ang[1] == (i0 + 1) % n_t)) | (
            (ang[1] == i0) & (ang[0] == (i0 + 1) % n_t))
        return np.flatnonzero(rim & crosses)

    def node_station_layer_angle(self, nodes):
        """Station, layer and angle index of node indices (vectorised)."""
        n_t = self.mesh.n_theta
        q, ang = np.divmod(np.asarray(nodes), n_t)
        st, layer = np.divmod(q, 2)
        return st, layer, ang
