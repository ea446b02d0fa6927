"""Strain-gauge sensor model: surface strain on the flexspline, grids, bridges, mV/V.

The truss's layer displacements give the surface strains of a shell of revolution (Flügge
1973) extrapolated to the face (:func:`face_strain_rows`); a grid measures the mean normal
strain along its axis (:func:`grid_row`); a bridge sums its arms, 1e3 · GF/4 · Σ ±ε_k
[mV/V], linearised (Hoffmann 1989; :func:`signal_rows`). :class:`SensorLayout` holds the
five bridges s0..s4 (the default :func:`default_signals`: the paper's Fig. 3 constraints
met on the back of the collar), :func:`gear_layout` a gear's with its tolerances.
Strains, bridges and the layout's table: docs/PHYSICS.md sec. 4.1-4.4.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.base.typed import check_range
from swgsim.gear.flexspline import INNER, OUTER, FlexsplineGeometry, TrussModel

sp = lazy_module("scipy.sparse")

# The default layout, written once (docs/PHYSICS.md sec. 4): bridge radii on the collar,
# active grid length, gauge factor of constantan foil gauges.
R_TORQUE_MM = 29.0     # radius of the s0 torque bridge [mm]
R_PAIRS_MM = 32.0      # radius of the s1..s4 half bridges [mm]
GRID_LENGTH_MM = 3.0   # active grid length [mm]
GAUGE_FACTOR = 2.0     # [-]
MIN_GRID_LENGTH_MM = 0.2  # shortest foil strain-gauge grids on the market [mm]
#: The sourced range of a bridge's zero offset bound [mV/V] (docs/PHYSICS.md sec. 4.4):
#: from a trimmed torque transducer's zero balance (±0.05 mV/V, Octogon FRB data sheet) to
#: the balance range an amplifier provides for an un-nulled 120-ohm bridge (±2.5 mV at
#: 2.5 V excitation = ±1.0 mV/V, NI SCC-SG01 user guide, Table 2) [src].
ZERO_OFFSET_RANGE_MVV = (0.05, 1.0)


@dataclass
class SensorsConfig:
    """Gauge layout of a data set (the data-set option ``sensors``), in millimetres.

    Attributes
    ----------
    r_torque_mm, r_pairs_mm : float
        Radii of the s0 torque bridge and of the s1..s4 half bridges [mm].
    grid_length_mm : float
        Active grid length [mm].
    gauge_factor : float
        Gauge factor GF [-].
    """

    r_torque_mm: float = R_TORQUE_MM
    r_pairs_mm: float = R_PAIRS_MM
    grid_length_mm: float = GRID_LENGTH_MM
    gauge_factor: float = GAUGE_FACTOR

    def check(self, where: str = "sensors") -> None:
        """The layout's own ranges, before a mesh resolves it (:func:`signal_rows`): radii
        inside the collar's clamped edge, a grid from :data:`MIN_GRID_LENGTH_MM` up to the
        collar's radial extent, a gauge factor of foil (about 2) up to semiconductor gauges
        (about 150; Hoffmann, *An Introduction to Measurements using Strain Gages*, HBM
        1989, sec. 2).

        Raises
        ------
        ValueError
            ``<where>.r_pairs_mm must lie in (0, ...] mm (inside the collar's clamped edge),
            got ...`` and the like.
        """
        geo = FlexsplineGeometry()
        r_c = geo.r_collar_m * 1e3
        for key in ("r_torque_mm", "r_pairs_mm"):
            check_range(getattr(self, key), 0.0, r_c, f"{where}.{key}", "mm", lo_open=True,
                        why="inside the collar's clamped edge")
        # no mesh resolves a grid shorter than the shortest foil grids sold or lays one
        # longer than the collar's radial extent (sleeve to clamped edge): the grid's own
        # range, so that the mesh (n_theta) is not blamed for it
        check_range(self.grid_length_mm, MIN_GRID_LENGTH_MM, r_c - geo.r_mid_m * 1e3,
                    f"{where}.grid_length_mm", "mm",
                    why="foil grids from 0.2 mm, no longer than the collar's radial extent")
        check_range(self.gauge_factor, 0.0, 200.0, f"{where}.gauge_factor", lo_open=True,
                    why="foil gauges about 2, semiconductor gauges up to about 150")


@dataclass
class TolerancesConfig:
    """Per-gear gauge tolerances, standard deviations (:meth:`SensorLayout.perturbed`).

    Attributes
    ----------
    sd_theta_deg : float
        Gauge angle [deg] (0.3, docs/simulation.md *Design choices*; unverified).
    sd_r_mm : float
        Gauge radius [mm].
    sd_beta_deg : float
        Grid orientation [deg].
    sd_gain : float
        Channel gain [-].
    zero_offset_mvv : float
        Bound of each bridge's zero offset [mV/V]: an un-nulled bridge's output at zero
        strain, drawn per bridge and gear uniformly in ±bound (the arms' resistance
        tolerance and the bonding; a tolerance stated as a bound, its distribution
        unknown). Default 0.525, the middle of the sourced range
        :data:`ZERO_OFFSET_RANGE_MVV` [src: range; choice: its middle]
        (docs/PHYSICS.md sec. 4.4); 0: balanced bridges.
    """

    sd_theta_deg: float = 0.3
    sd_r_mm: float = 0.1
    sd_beta_deg: float = 0.5
    sd_gain: float = 0.01
    zero_offset_mvv: float = 0.5 * (ZERO_OFFSET_RANGE_MVV[0] + ZERO_OFFSET_RANGE_MVV[1])

    def check(self, where: str = "tolerances") -> None:
        """Refuse a standard deviation or bound outside its range, naming
        ``<where>.<key>``; a zero offset up to 2.64 mV/V, the largest balance range of a
        bridge amplifier in the sources (NI SCC-SG02, 350-ohm bridges; docs/PHYSICS.md
        sec. 4.4).

        Raises
        ------
        ValueError
            ``<where>.sd_theta_deg must lie in [0, 5] deg, got ...`` and the like.
        """
        for key, hi, unit in (("sd_theta_deg", 5.0, "deg"), ("sd_r_mm", 2.0, "mm"),
                              ("sd_beta_deg", 10.0, "deg"), ("sd_gain", 0.2, ""),
                              ("zero_offset_mvv", 2.64, "mV/V")):
            check_range(getattr(self, key), 0.0, hi, f"{where}.{key}", unit)


@dataclass(frozen=True)
class Grid:
    """One strain-gauge grid on the back face of the collar.

    Attributes
    ----------
    r_m : float
        Radius of the grid centre [m].
    theta_deg : float
        Angular position of the grid centre in the flexspline frame [deg].
    beta_deg : float
        Grid axis measured from the radial direction towards +θ [deg].
    arm : int
        Bridge arm sign, +1 or −1.
    length_m : float
        Active grid length [m] (3 mm, a common torque-sensing grid).
    """

    r_m: float
    theta_deg: float
    beta_deg: float
    arm: int = 1
    length_m: float = GRID_LENGTH_MM * 1e-3


@dataclass(frozen=True)
class Signal:
    """One bridge signal.

    Attributes
    ----------
    name : str
        "s0".."s4".
    grids : tuple of Grid
        Active grids with their arm signs.
    bridge : str
        "quarter", "half" or "full" (documentation; the output is GF/4 Σ a_k ε_k).
    gain : float
        Gain of this channel relative to nominal [-] (per-gear tolerance).
    zero_offset_mvv : float
        The bridge's output at zero strain [mV/V] (per-gear tolerance): added to the
        strain's signal, not scaled by ``gain``.
    """

    name: str
    grids: tuple[Grid, ...]
    bridge: str
    gain: float = 1.0
    zero_offset_mvv: float = 0.0


def _shear_pair(r, th, length=GRID_LENGTH_MM * 1e-3):
    # arm signs chosen so that a positive output torque gives a positive signal
    return (Grid(r, th, -45.0, +1, length), Grid(r, th, 45.0, -1, length))


def _poisson_pair(r, th, length=GRID_LENGTH_MM * 1e-3):
    return (Grid(r, th, 0.0, +1, length), Grid(r, th, 90.0, -1, length))


@dataclass(frozen=True)
class SensorLayout:
    """The five bridge signals s0..s4 and the gauge factor.

    Attributes
    ----------
    signals : tuple of Signal
        s0..s4 in order (the default layout: docs/PHYSICS.md sec. 4.3).
    gauge_factor : float
        Gauge factor GF [-] (2.0, constantan foil gauges, docs/PHYSICS.md sec. 4).
    n_points : int
        Points sampled along each grid to average the strain.
    """

    signals: tuple[Signal, ...] = field(default_factory=lambda: default_signals())
    gauge_factor: float = GAUGE_FACTOR
    n_points: int = 9

    def __post_init__(self):
        if len(self.signals) != 5:
            raise ValueError(f"layout needs 5 signals s0..s4, got {len(self.signals)}")
        check_range(self.gauge_factor, 1.0, 5.0, "gauge_factor")

    def perturbed(self, rng: np.random.Generator,
                  tolerances: TolerancesConfig | None = None) -> SensorLayout:
        """A copy with per-gauge placement, per-channel gain and per-bridge zero offset
        tolerances.

        Models the paper's per-gear sensor models fitted to three real RT1-T gears
        (Sec. III-B): every grid is displaced by N(0, sd) in θ, r and orientation, every
        channel's gain is N(1, sd_gain). Gauge positioning is the dominant error of
        sensorised RT1-T gears (Schuller et al. 2024, docs/PHYSICS.md sec. 4). Every
        bridge's zero offset is U(−b, b), b = ``zero_offset_mvv``: an un-nulled bridge's
        imbalance (docs/PHYSICS.md sec. 4.4).

        Parameters
        ----------
        rng : numpy.random.Generator
            Draws, in the order grid (r, θ, β) by grid, then the channel's gain, signal
            by signal; then the five zero offsets (drawn last, so that the placements and
            gains are those of a layout without offsets).
        tolerances : TolerancesConfig, optional
            Standard deviations and the offset's bound; default :class:`TolerancesConfig`.
        """
        tol = tolerances if tolerances is not None else TolerancesConfig()
        sd_r_m, sd_theta_deg, sd_beta_deg = tol.sd_r_mm * 1e-3, tol.sd_theta_deg, tol.sd_beta_deg
        sd_gain = tol.sd_gain
        sigs = []
        for s in self.signals:
            grids = tuple(
                dataclasses.replace(
                    g,
                    r_m=g.r_m + sd_r_m * rng.standard_normal(),
                    theta_deg=g.theta_deg + sd_theta_deg * rng.standard_normal(),
                    beta_deg=g.beta_deg + sd_beta_deg * rng.standard_normal(),
                )
                for g in s.grids
            )
            sigs.append(dataclasses.replace(s, grids=grids,
                                            gain=s.gain * (1 + sd_gain * rng.standard_normal())))
        zero = tol.zero_offset_mvv * rng.uniform(-1.0, 1.0, size=len(sigs))
        sigs = [dataclasses.replace(s, zero_offset_mvv=s.zero_offset_mvv + float(z))
                for s, z in zip(sigs, zero, strict=True)]
        return dataclasses.replace(self, signals=tuple(sigs))

    @property
    def zero_offsets_mvv(self) -> np.ndarray:
        """The five bridges' zero offsets [mV/V], shape (5,)."""
        return np.array([s.zero_offset_mvv for s in self.signals], dtype=float)


def gear_layout(sensors: SensorsConfig, tolerances: TolerancesConfig,
                tolerance_seed: int) -> SensorLayout:
    """The layout of one gear: the data set's gauges with this gear's placement and gain
    errors (:meth:`SensorLayout.perturbed`, drawn from ``default_rng(tolerance_seed)``).

    Parameters
    ----------
    sensors : SensorsConfig
        Radii and grid length [mm], gauge factor.
    tolerances : TolerancesConfig
    tolerance_seed : int
        The gear's seed (its sensor model, paper Sec. III-B).

    Returns
    -------
    SensorLayout
    """
    sig = default_signals(sensors.r_torque_mm * 1e-3, sensors.r_pairs_mm * 1e-3)
    length = sensors.grid_length_mm * 1e-3
    sig = tuple(dataclasses.replace(x, grids=tuple(dataclasses.replace(g, length_m=length)
                                                   for g in x.grids)) for x in sig)
    lay = SensorLayout(signals=sig, gauge_factor=float(sensors.gauge_factor))
    return lay.perturbed(np.random.default_rng(int(tolerance_seed)), tolerances)


#: The five strain-gauge bridges' names, in the layout's order (:func:`default_signals`):
#: s0 the torque bridge, s1-s4 the half bridges at 0, 90, 180 and 270° (paper Sec. III-B).
SENSORS = ("s0", "s1", "s2", "s3", "s4")


def default_signals(r_torque_m: float = R_TORQUE_MM * 1e-3,
                    r_pairs_m: float = R_PAIRS_MM * 1e-3) -> tuple[Signal, ...]:
    """Default five-signal layout (docs/PHYSICS.md sec. 4.3); radii [m]."""
    s0, s1, s2, s3, s4 = SENSORS
    return (
        Signal(s0, _shear_pair(r_torque_m, 22.5) + _shear_pair(r_torque_m, 112.5), "full"),
        Signal(s1, _poisson_pair(r_pairs_m, 0.0), "half"),
        Signal(s2, _shear_pair(r_pairs_m, 90.0), "half"),
        Signal(s3, _poisson_pair(r_pairs_m, 180.0), "half"),
        Signal(s4, _shear_pair(r_pairs_m, 270.0), "half"),
    )


# ---------------------------------------------------------------------- strain rows
def strain_rows(model: TrussModel, layer: int, j: np.ndarray, xi: np.ndarray,
                theta: np.ndarray, beta: np.ndarray) -> sp.csr_matrix:
    """Rows giving the layer's normal strain at points of cells, in direction β.

    Parameters
    ----------
    model : TrussModel
    layer : int
        0 inner, 1 outer layer.
    j : ndarray of int, shape (n,)
        Station index of the cell (between stations j and j + 1).
    xi : ndarray, shape (n,)
        Position along the cell's meridian, 0..1.
    theta : ndarray, shape (n,)
        Angle of the point [rad].
    beta : ndarray, shape (n,)
        Direction from the meridian towards +θ [rad].

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n, n_dof)
        ε = rows @ u for displacements u in cylindrical components.
    """
    j, xi, theta, beta = (np.asarray(v) for v in np.broadcast_arrays(j, xi, theta, beta))
    n_t = model.mesh.n_theta
    dth = 2 * np.pi / n_t
    tpos = np.mod(theta, 2 * np.pi) / dth
    i0 = np.floor(tpos).astype(int) % n_t
    eta = tpos - np.floor(tpos)
    r0, r1 = model.layer_r[j, layer], model.layer_r[j + 1, layer]
    z0, z1 = model.layer_z[j, layer], model.layer_z[j + 1, layer]
    a = np.hypot(r1 - r0, z1 - z0)
    tr, tz = (r1 - r0) / a, (z1 - z0) / a
    r = r0 + xi * (r1 - r0)
    # shape functions and derivatives for nodes (j,i0), (j+1,i0), (j,i1), (j+1,i1)
    nn = [(1 - xi) * (1 - eta), xi * (1 - eta), (1 - xi) * eta, xi * eta]
    dxi = [-(1 - eta), (1 - eta), -eta, eta]
    deta = [-(1 - xi), -xi, (1 - xi), xi]
    nodes = [model.node(j, layer, i0), model.node(j + 1, layer, i0),
             model.node(j, layer, i0 + 1), model.node(j + 1, layer, i0 + 1)]
    c2, s2, cs = np.cos(beta) ** 2, np.sin(beta) ** 2, np.sin(beta) * np.cos(beta)
    rows, cols, vals = [], [], []
    idx = np.arange(j.size)
    for k in range(4):
        d_ds = dxi[k] / a
        d_dth = deta[k] / dth
        # coefficients of u_r, u_theta, u_z of node k in eps_ss, eps_tt, gamma
        e_ss = (tr * d_ds, 0 * d_ds, tz * d_ds)
        e_tt = (nn[k] / r, d_dth / r, 0 * r)
        g_st = (tr * d_dth / r, d_ds - nn[k] * tr / r, tz * d_dth / r)
        for comp in range(3):
            rows.append(idx)
            cols.append(3 * nodes[k] + comp)
            vals.append(c2 * e_ss[comp] + s2 * e_tt[comp] + cs * g_st[comp])
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(j.size, model.n_dof),
    )


def face_strain_rows(model: TrussModel, j, xi, theta, beta, face: str) -> sp.csr_matrix:
    """Normal strain of the wall face ("inner" −n side or "outer" +n side) at points.

    ε_face = ε_mid ± (t / 2h)(ε_outer − ε_inner), ε_mid = (ε_inner + ε_outer)/2, with t and
    h interpolated along the cell. On the collar the +n side is the front face (towards
    the toothed rim) and the −n ("inner") side is the back face.
    """
    if face not in ("inner", "outer"):
        raise ValueError(f"face must be 'inner' or 'outer', got {face!r}")
    j = np.asarray(j)
    xi = np.asarray(xi, dtype=float)
    t = (1 - xi) * model.mer["t"][j] + xi * model.mer["t"][j + 1]
    h = (1 - xi) * model.h[j] + xi * model.h[j + 1]
    e_in = strain_rows(model, INNER, j, xi, theta, beta)
    e_out = strain_rows(model, OUTER, j, xi, theta, beta)
    sgn = 1.0 if face == "outer" else -1.0
    w = sgn * t / (2 * h)
    return sp.diags(0.5 - w) @ e_in + sp.diags(0.5 + w) @ e_out


def collar_span(model: TrussModel) -> tuple[float, float]:
    """Radii [m] between which a grid may lie on the collar (away from corner and clamp)."""
    k = model.mer["corner"]
    r = model.mer["r"]
    return float(r[k + 1]), float(r[-2])


def grid_row(model: TrussModel, grid: Grid, n_points: int = 9) -> sp.csr_matrix:
    """Mean back-face strain along one grid on the collar.

    Parameters
    ----------
    model : TrussModel
    grid : Grid
    n_points : int
        Sampling points along the grid (midpoint rule).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (1, n_dof)

    Raises
    ------
    ValueError
        If the grid leaves the collar span, or if the truss is too coarse for it (a cell
        longer, radially, than the grid: the grid would not average over the strain field).
    """
    r_lo, r_hi = collar_span(model)
    b = np.deg2rad(grid.beta_deg)
    th0 = np.deg2rad(grid.theta_deg)
    sig = (np.arange(n_points) + 0.5) / n_points - 0.5
    sig = sig * grid.length_m
    # points along a straight grid in the collar plane
    x = grid.r_m + sig * np.cos(b)
    y = sig * np.sin(b)
    r = np.hypot(x, y)
    th = th0 + np.arctan2(y, x)
    beta_loc = b - np.arctan2(y, x)
    if r_hi - r_lo < grid.length_m:
        raise ValueError(
            f"truss too coarse for the gauge layout: the collar's usable span "
            f"{r_lo * 1e3:.2f}..{r_hi * 1e3:.2f} mm is shorter than a "
            f"{grid.length_m * 1e3:.1f} mm grid; raise mesh.n_theta")
    if r.min() < r_lo or r.max() > r_hi:
        raise ValueError(
            f"gauge grid at r = {grid.r_m * 1e3:.2f} mm (length {grid.length_m * 1e3:.1f} mm) "
            f"leaves the collar: allowed radii are {r_lo * 1e3:.2f}..{r_hi * 1e3:.2f} mm"
        )
    k = model.mer["corner"]
    rl = model.layer_r[k:, INNER]
    j = k + np.clip(np.searchsorted(rl, r) - 1, 0, rl.size - 2)
    cell = model.layer_r[j + 1, INNER] - model.layer_r[j, INNER]
    if cell.max() > grid.length_m:
        raise ValueError(
            f"truss too coarse for the gauge layout: radial cell size {cell.max() * 1e3:.2f} mm "
            f"exceeds the grid length {grid.length_m * 1e3:.2f} mm; raise mesh.n_theta"
        )
    xi = (r - model.layer_r[j, INNER]) / cell
    rows = face_strain_rows(model, j, xi, th, beta_loc, "inner")
    return sp.csr_matrix(rows.mean(axis=0))


def signal_rows(model: TrussModel, layout: SensorLayout) -> sp.csr_matrix:
    """Functionals of the five bridge signals, shape (5, n_dof): s [mV/V] = rows @ u [m]."""
    out = []
    for s in layout.signals:
        row = sum(g.arm * grid_row(model, g, layout.n_points) for g in s.grids)
        out.append(1e3 * layout.gauge_factor / 4.0 * s.gain * row)
    return sp.vstack(out).tocsr()
