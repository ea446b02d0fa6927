"""Lives that run to failure: a fault's severity grown by what the joint does.

``dataset.life.fault.growth`` ``paris`` (the cracks) or ``archard`` (the wave generator's
eccentricity, the flanks' wear) grows the fault from its severity at the onset by a law
driven by each window's operating point, acting load and temperature, up to a failure
severity at which it saturates (constants: :class:`RunToFailure`). Both are integrated
once per life on the window grid (:func:`paris_damage`, :func:`paris_crack_depth`,
:func:`archard_depth`; the life's severities :func:`grown_severity`). Laws, choices,
sources, the accelerated life: docs/DATASET.md, "Lives that run to failure".
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import LATER, check_range
from swgsim.gear.dynamics import GearParams
from swgsim.gear.faults import WEAR_BACKLASH_ARCMIN, ChainParams, get_fault
from swgsim.gear.flexspline import FlexsplineGeometry
from swgsim.gear.thermal import REF_TEMP_C, viscosity_ratio

__all__ = ["DEPTH_AT_ONE_M", "FAILURE_SEVERITY", "LAWS", "RunToFailure", "archard_depth",
           "arrhenius_factor", "check_to_failure", "draw_scale", "failure_hour",
           "film_factor", "grown_severity", "load_cycles", "paris_crack_depth",
           "paris_damage", "paris_threshold_depth"]

#: The law of each growth and the faults it grows.
LAWS: dict[str, tuple[str, ...]] = {"paris": ("root_tooth_crack", "tip_tooth_crack"),
                                    "archard": ("eccentric_wg", "wear")}

#: The molar gas constant [J/(mol K)] (CODATA 2018, exact) and 0 °C in kelvin.
GAS_CONSTANT, ZERO_C_K = 8.314462618, 273.15
#: Load cycles of a flexspline tooth per input revolution: the wave generator's two lobes
#: (each lobe meshes every flexspline tooth once a revolution) [derived].
CYCLES_PER_REV = 2.0

#: Depth of each law's fault at severity 1 [m]: a root crack through the rim's effective
#: thickness (the truss's, :class:`swgsim.gear.flexspline.FlexsplineGeometry`); a tip crack
#: through a tooth's depth, 0.5 mm, about two modules of the 200-tooth flexspline
#: [choice]; the wave generator's centre shifted by w0 (``eccentric_wg``'s severity is
#: e / w0, :class:`swgsim.gear.faults.ChainParams`); the flanks' lost thickness at the pitch
#: radius (:class:`swgsim.gear.dynamics.GearParams`) that gives ``wear``'s backlash at
#: severity 1 (3 arcmin: 22 µm) [derived].
DEPTH_AT_ONE_M: dict[str, float] = {
    "root_tooth_crack": FlexsplineGeometry.t_rim_m,
    "tip_tooth_crack": 0.5e-3,
    "eccentric_wg": ChainParams.w0_m,
    "wear": GearParams.pitch_radius_m * float(np.deg2rad(WEAR_BACKLASH_ARCMIN / 60.0)),
}

#: Severity at which each fault fails, the default of ``to_failure.failure`` [choice]: a
#: root crack through half the rim, a tip crack through 80 % of the tooth, the wave
#: generator 30 % of w0 off centre (76 µm), 80 % of the wear that gives 3 arcmin backlash.
FAILURE_SEVERITY: dict[str, float] = {"root_tooth_crack": 0.5, "tip_tooth_crack": 0.8,
                                      "eccentric_wg": 0.3, "wear": 0.8}


@dataclass
class RunToFailure:
    """The constants of a fault's growth to failure (DATASET.md, "Lives that run to failure").

    Attributes
    ----------
    failure : float or None
        Failure severity, above the severity at the onset and within the fault's range;
        None: :data:`FAILURE_SEVERITY` of the fault [choice].
    scatter : float
        σ of the lognormal factor on C or the wear coefficient, per gear, in [0, 2] (0.3:
        a factor 0.55-1.8 for ±2σ) [choice: crack-growth rates of identical specimens
        scatter by about a factor of 2, Virkler, Hillberry and Goel, J. Eng. Mater.
        Technol. 101 (1979) 148-153 [unverified: recalled]].
    paris_c : float
        C of Paris' law [m/cycle per (MPa √m)^m] (6.9e-12, ferrite-pearlite steels,
        Barsom and Rolfe, "Fracture and Fatigue Control in Structures" [unverified:
        recalled]).
    paris_m : float
        m of Paris' law, in [1, 6] [-] (3, steels, the same source).
    shape_factor : float
        Y of ΔK = Y Δσ √(π a), in (0, 5] [-] (1.12, an edge crack, Tada, Paris and Irwin,
        "The Stress Analysis of Cracks Handbook" [unverified: recalled]).
    stress_mpa_per_nm : float
        Δσ at the tooth per N m of acting load, in (0, 100] [MPa/(N m)] (0.6: 31 MPa at
        the rated 52 N m) [choice: sets the accelerated life of
        DATASET.md, "Lives that run to failure"].
    wear_coeff_m_per_nm_rev : float
        Worn depth per N m of acting load per input revolution at 20 °C, in (0, 1e-9]
        [m/(N m rev)] (2e-14) [choice: the accelerated life of
        DATASET.md, "Lives that run to failure"].
    film_exponent : float
        p of the film factor (ν(T)/ν(20 °C))^(−p), in [0, 3] [-] (0.67,
        DATASET.md, "Lives that run to failure").
    threshold_sif : float
        ΔK_th of the Klesnil-Lukáš law da/dN = C (ΔK^m − ΔK_th^m), no growth below it,
        in [0, 100] [MPa √m] (0: Paris' law) (Klesnil and Lukáš, Eng. Fract. Mech. 4
        (1972) 77-92; :func:`paris_threshold_depth`).
    activation_kj_per_mol : float or None
        Q of an Arrhenius factor exp(−Q/R (1/T − 1/T_20)) on the wear rate in place of the
        film factor, in [1, 200] [kJ/mol] (oxidational wear, Quinn, Wear 18 (1971)
        413-419); None: the film factor.
    """

    failure: float | None = None
    scatter: float = 0.3
    paris_c: float = 6.9e-12
    paris_m: float = 3.0
    shape_factor: float = 1.12
    stress_mpa_per_nm: float = 0.6
    wear_coeff_m_per_nm_rev: float = 2e-14
    film_exponent: float = 0.67
    threshold_sif: float = field(default=0.0, metadata={LATER: "issue 85"})
    activation_kj_per_mol: float | None = field(default=None, metadata={LATER: "issue 85"})

    def failure_severity(self, fault: str) -> float:
        """The failure severity of ``fault``: ``failure`` or its default [-]."""
        return float(FAILURE_SEVERITY[fault] if self.failure is None else self.failure)


def check_to_failure(cfg: RunToFailure, fault: str, growth: str, initial: float,
                     key: str) -> None:
    """Refuse a growth to failure outside its ranges, in one line naming the key.

    Parameters
    ----------
    cfg : RunToFailure
    fault, growth : str
        The life's fault and its growth (a key of :data:`LAWS`).
    initial : float
        Severity at the onset [-].
    key : str
        Full name of the fault entry, e.g. ``dataset.life.fault``.

    Raises
    ------
    ValueError
        The law not for this fault, a crack of severity 0 at the onset, a failure severity
        at or below the onset's or outside the fault's range, a constant out of range.
    """
    if fault not in LAWS[growth]:
        others = [g for g, fs in LAWS.items() if fault in fs]
        raise ValueError(f"{key}.growth={growth} grows {', '.join(LAWS[growth])}, not {fault}; "
                         f"allowed for {fault}: {['step', 'linear', 'points', *others]}")
    hi = get_fault(fault).severity_range[1]
    if growth == "paris":
        check_range(initial, 0.0, hi, f"{key}.severity", lo_open=True,
                    why="the crack at the onset; Paris' law grows no crack from 0")
    fail = cfg.failure_severity(fault)
    check_range(fail, initial, hi, f"{key}.to_failure.failure", lo_open=True,
                why=f"above the severity at the onset, within {fault}'s range")
    check_range(cfg.scatter, 0.0, 2.0, f"{key}.to_failure.scatter")
    check_range(cfg.paris_c, 0.0, 1e-6, f"{key}.to_failure.paris_c", "m/cycle", lo_open=True)
    check_range(cfg.paris_m, 1.0, 6.0, f"{key}.to_failure.paris_m")
    check_range(cfg.shape_factor, 0.0, 5.0, f"{key}.to_failure.shape_factor", lo_open=True)
    check_range(cfg.stress_mpa_per_nm, 0.0, 100.0, f"{key}.to_failure.stress_mpa_per_nm",
                "MPa/(N m)", lo_open=True)
    check_range(cfg.wear_coeff_m_per_nm_rev, 0.0, 1e-9,
                f"{key}.to_failure.wear_coeff_m_per_nm_rev", "m/(N m rev)", lo_open=True)
    check_range(cfg.film_exponent, 0.0, 3.0, f"{key}.to_failure.film_exponent")
    check_range(cfg.threshold_sif, 0.0, 100.0, f"{key}.to_failure.threshold_sif", "MPa √m")
    if cfg.activation_kj_per_mol is not None:
        check_range(cfg.activation_kj_per_mol, 1.0, 200.0,
                    f"{key}.to_failure.activation_kj_per_mol", "kJ/mol")


def load_cycles(n_in_rpm: np.ndarray, minutes: float) -> np.ndarray:
    """Load cycles of a flexspline tooth in ``minutes`` at input speeds ``n_in_rpm``,
    2 per input revolution (:data:`CYCLES_PER_REV`), shape of ``n_in_rpm`` [-]."""
    return CYCLES_PER_REV * np.abs(np.asarray(n_in_rpm, float)) * float(minutes)


def paris_damage(cycles: np.ndarray, delta_sigma_mpa: np.ndarray, c: float,
                 m: float) -> np.ndarray:
    """Paris' damage sum after each block, D_k = Σ_{i<=k} C Δσ_i^m ΔN_i
    (DATASET.md, "Lives that run to failure").

    Parameters
    ----------
    cycles, delta_sigma_mpa : ndarray, shape (K,)
        Load cycles ΔN_i of each block [-] and their stress range Δσ_i [MPa].
    c, m : float
        Paris' C [m/cycle per (MPa √m)^m] and m [-].

    Returns
    -------
    ndarray, shape (K,)
        D after each block [m^(1 − m/2)] (the crack depth from it: :func:`paris_crack_depth`).
    """
    return np.cumsum(c * np.asarray(delta_sigma_mpa, float) ** m * np.asarray(cycles, float))


def paris_crack_depth(a0_m: float, damage: np.ndarray, m: float, y: float) -> np.ndarray:
    """Crack depth after a damage sum, the closed form of da/dN = C (Y Δσ √(π a))^m.

    a^(1 − m/2) = a0^(1 − m/2) + (1 − m/2) (Y √π)^m D for m ≠ 2, a = a0 exp((Y √π)^2 D)
    for m = 2 [derived: separation of variables]; at constant Δσ, D = C Δσ^m N gives the
    textbook a(N).

    Parameters
    ----------
    a0_m : float
        Depth at D = 0, > 0 [m].
    damage : ndarray, shape (K,)
        D (:func:`paris_damage`) [m^(1 − m/2)].
    m, y : float
        Paris' m and the shape factor Y [-].

    Returns
    -------
    ndarray, shape (K,)
        Crack depth [m]; inf where the crack has grown without bound (m > 2).
    """
    d = np.asarray(damage, float)
    k = (y * np.sqrt(np.pi)) ** m
    if m == 2.0:
        return a0_m * np.exp(k * d)
    e = 1.0 - m / 2.0
    base = a0_m ** e + e * k * d
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(base > 0, np.abs(base) ** (1.0 / e), np.inf)


def paris_threshold_depth(a0_m: float, cycles: np.ndarray, delta_sigma_mpa: np.ndarray,
                          c: float, m: float, y: float, threshold_sif: float,
                          stop_m: float = np.inf, substeps: int = 4) -> np.ndarray:
    """Crack depth after each block by the Klesnil-Lukáš law
    da/dN = C (ΔK^m − ΔK_th^m), ΔK = Y Δσ √(π a), no growth where ΔK ≤ ΔK_th.

    No closed form: each block (Δσ held) is integrated by ``substeps`` classic Runge-Kutta
    steps in u = a^(1 − m/2) (ln a for m = 2), where the law without a threshold is a
    straight line (:func:`paris_crack_depth`: exact there, to rounding)
    [derived]: du/dN = (1 − m/2) C ((Y √π Δσ)^m − ΔK_th^m a^(−m/2)).

    Parameters
    ----------
    a0_m : float
        Depth before the first block, > 0 [m].
    cycles, delta_sigma_mpa : ndarray, shape (K,)
        Load cycles ΔN_i of each block [-] and their stress range Δσ_i [MPa].
    c, m, y : float
        Paris' C [m/cycle per (MPa √m)^m], m [-] and the shape factor Y [-].
    threshold_sif : float
        ΔK_th [MPa √m] (0: :func:`paris_crack_depth`'s law).
    stop_m : float
        Depth beyond which nothing more is integrated: every later block reads inf [m]
        (a failure depth: the blocks after failure are not needed).
    substeps : int
        Runge-Kutta steps per block, >= 1.

    Returns
    -------
    ndarray, shape (K,)
        Depth after each block [m]; inf once beyond ``stop_m`` or grown without bound.

    Source: Klesnil and Lukáš, Eng. Fract. Mech. 4 (1972) 77-92.
    """
    n = np.asarray(cycles, float)
    ds = np.asarray(delta_sigma_mpa, float)
    e = 1.0 - m / 2.0
    k = (y * np.sqrt(np.pi)) ** m
    th = float(threshold_sif) ** m
    to_a = (lambda u: np.exp(u)) if e == 0 else (lambda u: u ** (1.0 / e) if u > 0 else np.inf)
    u = np.log(a0_m) if e == 0 else a0_m ** e
    slope = 1.0 if e == 0 else e
    out = np.full(n.shape, np.inf)

    def rate(u_: float, drive: float) -> float:  # du/dN
        a = to_a(u_)
        if not np.isfinite(a):
            return 0.0
        return slope * c * max(drive - th * a ** (-m / 2.0), 0.0)

    for i in range(n.size):
        drive, h = k * ds[i] ** m, n[i] / substeps
        for _ in range(int(substeps)):
            k1 = rate(u, drive)
            k2 = rate(u + 0.5 * h * k1, drive)
            k3 = rate(u + 0.5 * h * k2, drive)
            k4 = rate(u + h * k3, drive)
            u += h * (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
        a = to_a(u)
        if not a <= stop_m:
            break
        out[i] = a
    return out


def arrhenius_factor(temp_c: np.ndarray, activation_kj_per_mol: float,
                     ref_c: float = REF_TEMP_C) -> np.ndarray:
    """Factor on a wear rate at a temperature, exp(−Q/R (1/T − 1/T_ref)), T in kelvin,
    shape of ``temp_c`` [-] (1 at ``ref_c``).

    Source: Quinn, "Oxidational wear", Wear 18 (1971) 413-419 (the rate of the oxide's
    growth, Arrhenius in the contact's temperature)."""
    t = np.asarray(temp_c, float) + ZERO_C_K
    q = float(activation_kj_per_mol) * 1e3 / GAS_CONSTANT
    return np.exp(-q * (1.0 / t - 1.0 / (float(ref_c) + ZERO_C_K)))


def film_factor(temp_c: np.ndarray, exponent: float) -> np.ndarray:
    """Factor on the wear rate at a grease temperature, (ν(T)/ν(20 °C))^(−p), shape of
    ``temp_c`` [-] (:func:`swgsim.gear.thermal.viscosity_ratio`; ValueError outside its
    −40..150 °C)."""
    return viscosity_ratio(temp_c) ** (-float(exponent))


def archard_depth(t_acting_nm: np.ndarray, revolutions: np.ndarray, temp_c: np.ndarray,
                  coeff: float, exponent: float, activation_kj_per_mol: float | None = None
                  ) -> np.ndarray:
    """Worn depth after each block by Archard's law, Σ k abs(T) n_rev film(T_grease)
    (or, with an activation energy, its Arrhenius factor in place of the film factor).

    Parameters
    ----------
    t_acting_nm, revolutions, temp_c : ndarray, shape (K,)
        Acting load [N m], input revolutions [-] and grease temperature [°C] of each block.
    coeff : float
        k [m/(N m rev)] at 20 °C.
    exponent : float
        The film factor's p (:func:`film_factor`).
    activation_kj_per_mol : float or None
        Q of :func:`arrhenius_factor`, used in place of the film factor; None: the film
        factor.

    Returns
    -------
    ndarray, shape (K,)
        Depth after each block [m].
    """
    rate = coeff * np.abs(np.asarray(t_acting_nm, float)) * np.asarray(revolutions, float)
    temp = (film_factor(temp_c, exponent) if activation_kj_per_mol is None
            else arrhenius_factor(temp_c, activation_kj_per_mol))
    return np.cumsum(rate * temp)


def grown_severity(fault: str, growth: str, cfg: RunToFailure, onset_h: float,
                   initial: float, hours: np.ndarray, interval_min: float,
                   n_in_rpm: np.ndarray, t_acting_nm: np.ndarray, temp_c: np.ndarray,
                   scale: float = 1.0) -> np.ndarray:
    """The exact severity of a fault growing to failure at each window of a life.

    Window k holds what grew over the windows before it since the onset, each holding its
    operating point, load and temperature for ``interval_min``; 0 before the onset,
    ``initial`` at the first window from it, the failure severity from failure on.

    Parameters
    ----------
    fault, growth : str
        A fault of ``LAWS[growth]`` (checked, :func:`check_to_failure`).
    cfg : RunToFailure
    onset_h, initial : float
        Onset [h] and the severity then [-].
    hours, n_in_rpm, t_acting_nm, temp_c : ndarray, shape (W,)
        Each window's operating hour [h], input speed [rpm], acting load [N m] and grease
        temperature [°C].
    interval_min : float
        Operating minutes between windows [min].
    scale : float
        The gear's factor on C or the wear coefficient (:func:`draw_scale`) [-].

    Returns
    -------
    ndarray, shape (W,)
        Severity [-].
    """
    h = np.asarray(hours, float)
    on = h >= onset_h
    depth0 = initial * DEPTH_AT_ONE_M[fault]
    grown = np.zeros(h.shape)
    n = np.where(on, np.asarray(n_in_rpm, float), 0.0)
    if growth == "paris" and cfg.threshold_sif > 0:
        start = int(np.argmax(on)) if on.any() else h.size
        a = paris_threshold_depth(
            depth0, load_cycles(n[start:-1], interval_min),
            cfg.stress_mpa_per_nm * np.abs(np.asarray(t_acting_nm, float)[start:-1]),
            scale * cfg.paris_c, cfg.paris_m, cfg.shape_factor, cfg.threshold_sif,
            stop_m=cfg.failure_severity(fault) * DEPTH_AT_ONE_M[fault])
        grown[start + 1:] = a - depth0
    elif growth == "paris":
        dmg = paris_damage(load_cycles(n, interval_min),
                           cfg.stress_mpa_per_nm * np.abs(t_acting_nm), scale * cfg.paris_c,
                           cfg.paris_m)
        a = paris_crack_depth(depth0, dmg[:-1], cfg.paris_m, cfg.shape_factor)
        grown[1:] = np.where(dmg[:-1] > 0, a - depth0, 0.0)  # exactly the onset's before
    else:
        revs = np.abs(n) * float(interval_min)
        grown[1:] = archard_depth(t_acting_nm, revs, temp_c,
                                  scale * cfg.wear_coeff_m_per_nm_rev, cfg.film_exponent,
                                  cfg.activation_kj_per_mol)[:-1]
    sev = np.minimum(initial + grown / DEPTH_AT_ONE_M[fault], cfg.failure_severity(fault))
    return np.where(on, sev, 0.0)


def failure_hour(hours: np.ndarray, severity: np.ndarray, failure: float) -> float:
    """The first operating hour at which a severity reaches the failure severity.

    Parameters
    ----------
    hours : ndarray, shape (W,)
        Operating hour of each window [h].
    severity : ndarray, shape (W,)
        Severity at each window [-].
    failure : float
        Failure severity [-] (reached: severity >= failure).

    Returns
    -------
    float
        The hour of the first window at or above ``failure`` [h]; NaN where none is.
    """
    hit = np.flatnonzero(np.asarray(severity) >= failure)
    return float(np.asarray(hours)[hit[0]]) if hit.size else float("nan")


def draw_scale(cfg: RunToFailure, rng: np.random.Generator) -> float:
    """The gear's lognormal factor on C or the wear coefficient, exp(``scatter`` z), z one
    standard normal draw of ``rng`` [-] (median 1)."""
    return float(np.exp(cfg.scatter * rng.standard_normal()))
