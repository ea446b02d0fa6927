"""Prognosis after an alarm: the hours left until the named fault's severity reaches its
failure threshold, as a distribution (in the stream: :mod:`.stream`).

:func:`predict_growth` takes the fault's growth law from :mod:`swgsim.datasets.growth`
(Paris' law for the cracks, Archard's for the eccentricity and wear) with one unknown, the
gear's scale s; in a transformed severity (:func:`transformed`) the law is a straight line
in the exposure the duty gave, ln s gets a grid posterior, Monte-Carlo draws give the
remaining hours. Baselines: :mod:`.baselines`. Design, formulas and
assumptions (and why not ProgPy or SurPyval): docs/monitor/prognosis.md, "Prognosis".
"""

from __future__ import annotations

import dataclasses

import numpy as np

from swgmon.prognosis.inputs import (
    Duty,
    DutyRange,
    Prognosis,
    PrognosisConfig,
    Track,
    check_track,
    from_samples,
    not_valid,
    not_yet_valid,
)
from swgsim.datasets.growth import (
    DEPTH_AT_ONE_M,
    LAWS,
    RunToFailure,
    archard_depth,
    load_cycles,
    paris_damage,
)

__all__ = ["Duty", "DutyRange", "Prognosis", "PrognosisConfig", "Track", "check_track",
           "exposure", "from_samples", "hours_for_exposure", "not_valid", "not_yet_valid",
           "predict_growth", "residual_correlation", "severity_of", "transformed"]

#: z of a central 90 % interval of a normal distribution, its half-width in σ [-]: the
#: standard normal's 95 % quantile, scipy.special.ndtri(0.95) (written in: an app's start
#: imports no scipy, tests/apps/test_startup.py).
Z90 = 1.6448536269514722



# ------------------------------------------------------------------ the growth law


def _law(fault: str) -> str:
    """The growth law of ``fault`` (a key of :data:`LAWS`)."""
    return next(g for g, fs in LAWS.items() if fault in fs)


def transformed(fault: str, severity: np.ndarray, tf: RunToFailure, floor: float
                ) -> tuple[np.ndarray, float]:
    """The severity in which the fault's law is a straight line in the exposure.

    Parameters
    ----------
    fault : str
        A fault of :data:`swgsim.datasets.growth.LAWS`.
    severity : ndarray, shape (n,)
        Severity [-] (a crack's floored at ``floor``).
    tf : RunToFailure
        The law's constants.
    floor : float
        The least severity of a crack (:attr:`PrognosisConfig.severity_floor`) [-].

    Returns
    -------
    u : ndarray, shape (n,)
        Archard: the severity; Paris: (severity d1)^(1 − m/2), ln(severity d1) for m = 2
        (docs/monitor/prognosis.md, "Prognosis") [derived].
    b : float
        du/dX per unit scale: u = u0 + b s X [-/exposure].
    """
    sev = np.asarray(severity, float)
    d1 = DEPTH_AT_ONE_M[fault]
    if _law(fault) == "archard":
        return sev, 1.0 / d1
    a = np.maximum(sev, floor) * d1
    k = (tf.shape_factor * np.sqrt(np.pi)) ** tf.paris_m
    if tf.paris_m == 2.0:
        return np.log(a), float(k)
    e = 1.0 - tf.paris_m / 2.0
    return a ** e, float(e * k)


def exposure(fault: str, duty: Duty, tf: RunToFailure) -> np.ndarray:
    """The exposure at s = 1 after each block of a duty, cumulative.

    Parameters
    ----------
    fault : str
        A fault of :data:`swgsim.datasets.growth.LAWS`.
    duty : Duty
        K blocks.
    tf : RunToFailure
        The law's constants.

    Returns
    -------
    ndarray, shape (K,)
        Paris: the damage sum D (:func:`swgsim.datasets.growth.paris_damage`, two load
        cycles per input revolution, Δσ = ``stress_mpa_per_nm`` · abs(load)) [m^(1 − m/2)];
        Archard: the worn depth (:func:`swgsim.datasets.growth.archard_depth`) [m].
    """
    minutes = np.asarray(duty.minutes, float)
    if _law(fault) == "paris":
        cycles = load_cycles(duty.n_in_rpm, 1.0) * minutes
        return paris_damage(cycles, tf.stress_mpa_per_nm * np.abs(duty.t_acting_nm),
                            tf.paris_c, tf.paris_m)
    revs = np.abs(np.asarray(duty.n_in_rpm, float)) * minutes
    return archard_depth(duty.t_acting_nm, revs, duty.temp_c, tf.wear_coeff_m_per_nm_rev,
                         tf.film_exponent)


def hours_for_exposure(need: np.ndarray, duty: Duty, cum: np.ndarray) -> np.ndarray:
    """Operating hours for a duty, repeated as a cycle from its start, to add exposure.

    Parameters
    ----------
    need : ndarray, shape (N,)
        Exposure to add at s = 1 (≤ 0: none) [as :func:`exposure`].
    duty : Duty
        The future duty, K blocks.
    cum : ndarray, shape (K,)
        :func:`exposure` of ``duty``.

    Returns
    -------
    ndarray, shape (N,)
        Hours [h]: 0 where nothing is needed, inf where the duty adds no exposure.
    """
    cum_e = np.concatenate([[0.0], cum])
    cum_h = np.concatenate([[0.0], np.cumsum(duty.minutes) / 60.0])
    per_cycle = cum_e[-1]
    need = np.where(np.isnan(need), np.inf, need)
    if per_cycle <= 0:
        return np.where(need > 0, np.inf, 0.0)
    finite = np.isfinite(need) & (need > 0)
    x = np.where(finite, need, 0.0)
    n = np.floor(x / per_cycle)
    rem = x - n * per_cycle
    i = np.clip(np.searchsorted(cum_e, rem, side="left"), 1, cum_e.size - 1)  # block of rem
    de = cum_e[i] - cum_e[i - 1]
    frac = np.divide(rem - cum_e[i - 1], de, out=np.zeros_like(rem), where=de > 0)
    t = n * cum_h[-1] + cum_h[i - 1] + np.clip(frac, 0.0, 1.0) * (cum_h[i] - cum_h[i - 1])
    return np.where(finite, t, np.where(need > 0, np.inf, 0.0))


def _track_exposure(fault: str, hours: np.ndarray, recorded: Duty, windows_h: np.ndarray,
                    tf: RunToFailure) -> np.ndarray:
    """Exposure since the first recorded window at each estimate hour, shape (n,): each
    window's own grows over its interval (linear within it)."""
    cum = exposure(fault, recorded, tf)
    xp = np.append(windows_h, windows_h[-1] + recorded.minutes[-1] / 60.0)
    return np.interp(hours, xp, np.concatenate([[0.0], cum]))


def severity_of(fault: str, u: np.ndarray, tf: RunToFailure) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of :func:`transformed`.

    Parameters
    ----------
    fault : str
        A fault of :data:`swgsim.datasets.growth.LAWS`.
    u : ndarray, any shape
        Transformed severity (:func:`transformed`).
    tf : RunToFailure
        The law's constants.

    Returns
    -------
    severity, slope : ndarray, each of ``u``'s shape
        Severity [-] and d(severity)/du; a crack grown without bound (u ≤ 0 for m > 2)
        clipped at severity 10^3 [choice: far beyond any failure severity], its slope 0.
    """
    v = np.asarray(u, float)
    if _law(fault) == "archard":
        return v, np.ones_like(v)
    d1, m = DEPTH_AT_ONE_M[fault], tf.paris_m
    if m == 2.0:
        sev = np.exp(np.minimum(v, np.log(1e3 * d1))) / d1
        return sev, sev
    e = 1.0 - m / 2.0
    v_cap = (1e3 * d1) ** e  # u of severity 10^3
    vc = np.maximum(v, v_cap) if e < 0 else np.minimum(v, v_cap)
    sev = vc ** (1.0 / e) / d1
    return sev, np.where(vc == v, sev / (e * vc), 0.0)


def _grid_posterior(ls: np.ndarray, y: np.ndarray, w: np.ndarray, x: np.ndarray,
                    fault: str, cfg: PrognosisConfig, tf: RunToFailure
                    ) -> tuple[np.ndarray, ...]:
    """Log posterior of ln s at grid ``ls`` (shape (G,); not normalised: the prior
    and the likelihood's sum of squares, u0 integrated out under a flat prior by
    Laplace's method), u0's fit and precision there, each shape (G,); y, w = 1/σ², x: the
    estimates, shape (n,), under the law ``tf`` (docs/monitor/prognosis.md, "Prognosis")."""
    floor = cfg.severity_floor
    u, b = transformed(fault, y, tf, floor)
    beta = b * np.exp(ls)[:, None]  # (G, 1)
    early = slice(0, max(3, y.size // 4))  # the start: the first quarter's mean [choice]
    u0 = transformed(fault, np.array([w[early] @ y[early] / w[early].sum()]), tf, floor)[0] \
        - beta[:, 0] * (w[early] @ x[early] / w[early].sum())
    for _ in range(cfg.gauss_newton_steps):
        sev, jac = severity_of(fault, u0[:, None] + beta * x, tf)  # (G, n)
        wj = w * jac
        u0 = u0 + (wj * (y - sev)).sum(axis=1) / np.maximum((wj * jac).sum(axis=1), 1e-300)
    sev, jac = severity_of(fault, u0[:, None] + beta * x, tf)
    info = np.maximum((w * jac ** 2).sum(axis=1), 1e-300)
    prior_sd = max(tf.scatter, 1e-3)  # scatter 0: the scale known [choice]
    logp = -0.5 * (w * (y - sev) ** 2).sum(axis=1) - 0.5 * np.log(info) \
        - 0.5 * (ls / prior_sd) ** 2
    return logp, u0, info


def residual_correlation(y: np.ndarray, w: np.ndarray, x: np.ndarray, fault: str,
                         cfg: PrognosisConfig, ls: np.ndarray) -> float:
    """Lag-1 autocorrelation of the standardised residuals at the posterior's peak over
    grid ``ls``, under the law ``cfg.to_failure``, in [0, ``cfg.max_correlation``] [-].

    Neighbouring severity estimates are read by one regressor from windows of one gear
    in one state: their errors are correlated, not independent as the likelihood of
    :func:`_grid_posterior` takes them. An AR(1) error with coefficient ρ carries the
    information of n (1 − ρ) / (1 + ρ) independent ones about a level or a slope (the
    effective sample size; Box, Jenkins and Reinsel, "Time Series Analysis", 4th ed.,
    Wiley 2008, sec. 2.1.5), so the fit's weights are scaled by that factor
    (:func:`predict_growth`). A negative ρ is taken as 0 (no gain claimed).
    """
    tf = cfg.to_failure
    logp, u0, _ = _grid_posterior(ls, y, w, x, fault, cfg, tf)
    k = int(np.argmax(logp))
    b = transformed(fault, y, tf, cfg.severity_floor)[1]
    sev, _ = severity_of(fault, u0[k] + b * np.exp(ls[k]) * x, tf)
    z = (y - sev) * np.sqrt(w)
    z = z - z.mean()
    if z.size < 3 or not np.any(z):
        return 0.0
    return float(np.clip((z[1:] @ z[:-1]) / (z @ z), 0.0, cfg.max_correlation))


def _paris_laws(fault: str, tf: RunToFailure, cfg: PrognosisConfig, y: np.ndarray,
                thr: float, recorded: Duty) -> tuple[list[RunToFailure], np.ndarray]:
    """The laws a prognosis weighs, M of them, and their log prior, shape (M,): for a
    crack with ``cfg.paris_m_sd`` > 0, Paris' m on ``paris_m_points`` points over the
    prior's mean ``tf.paris_m`` ± 2σ (within [1, 6]); else ``tf`` alone.

    C moves with m about a pivot ΔK (the C-m correlation, Cortie and Garrett, Eng. Fract.
    Mech. 30 (1988) 49-58 [unverified: recalled]), so the scale's prior means one rate
    whatever m. The material's pivot is unknown; the crack's own mid-life stands for it:
    Y Δσ √(π a) at the ``recorded`` duty's mean load and the geometric mean of the depths
    at the start (the median of the first quarter of the estimates ``y``) and at failure
    (``thr``) [choice]."""
    load_nm = np.sum(np.abs(recorded.t_acting_nm) * recorded.minutes) / np.sum(recorded.minutes)
    if _law(fault) == "archard" or cfg.paris_m_sd == 0 or cfg.paris_m_points == 1 \
            or load_nm <= 0:
        return [tf], np.zeros(1)
    start = float(np.median(y[:max(3, y.size // 4)]))
    m = np.clip(tf.paris_m + cfg.paris_m_sd * np.linspace(-2.0, 2.0, cfg.paris_m_points),
                1.0, 6.0)
    depth = DEPTH_AT_ONE_M[fault] * np.sqrt(max(start, cfg.severity_floor) * thr)
    pivot = tf.shape_factor * tf.stress_mpa_per_nm * load_nm * np.sqrt(np.pi * depth)
    laws = [dataclasses.replace(tf, paris_m=float(mi),
                                paris_c=float(tf.paris_c * pivot ** (tf.paris_m - mi)))
            for mi in m]
    return laws, -0.5 * ((m - tf.paris_m) / cfg.paris_m_sd) ** 2


def _posterior(y: np.ndarray, w: np.ndarray, x: np.ndarray, fault: str,
               cfg: PrognosisConfig, tf: RunToFailure) -> tuple[np.ndarray, ...]:
    """The grid posterior of ln s under ``tf`` over ±``log_scale_span``, then again on
    ``n_grid`` points over where it exceeds e^-25 of its peak (a cell beyond each end)
    [choice: a precise track's posterior is narrower than a coarse cell]: the grid, its
    log posterior, u0 and its precision (shape (G,) each), and the log evidence
    (the posterior's integral, with u0's prior flat in the starting severity: the
    Jacobian d severity / d u0 at the peak) [-]."""
    ls = np.linspace(-cfg.log_scale_span, cfg.log_scale_span, cfg.n_grid)
    logp, _, _ = _grid_posterior(ls, y, w, x, fault, cfg, tf)
    keep = np.flatnonzero(logp > logp.max() - 25.0)
    cell = ls[1] - ls[0]
    ls = np.linspace(ls[keep[0]] - cell, ls[keep[-1]] + cell, cfg.n_grid)
    logp, u0, info = _grid_posterior(ls, y, w, x, fault, cfg, tf)
    k = int(np.argmax(logp))
    slope = abs(float(severity_of(fault, u0[k:k + 1], tf)[1][0]))
    peak = float(logp[k])
    evidence = peak + np.log(np.exp(logp - peak).sum() * (ls[1] - ls[0])) \
        + np.log(max(slope, 1e-300))
    return ls, logp - peak, u0, info, evidence


def _draws(post: tuple[np.ndarray, ...], n: int, rng: np.random.Generator
           ) -> tuple[np.ndarray, np.ndarray]:
    """n draws of (s, u0) from a :func:`_posterior`: ln s from the grid (uniform within
    a cell), u0 given s normal about its fit (Laplace's method)."""
    ls, logp, u0, info, _ = post
    p = np.exp(logp)
    pick = rng.choice(ls.size, size=n, p=p / p.sum())
    s = np.exp(ls[pick] + (ls[1] - ls[0]) * (rng.random(n) - 0.5))
    return s, u0[pick] + rng.standard_normal(n) / np.sqrt(info[pick])


def _failures(thr: float, now: float, cfg: PrognosisConfig, n: int,
              rng: np.random.Generator) -> np.ndarray:
    """n failure severities [-]: the threshold, or with ``cfg.failure_ratios`` the
    threshold times ratios drawn among those above the last estimate ``now`` (the largest
    where none is)."""
    r = np.asarray(cfg.failure_ratios, float)
    if not r.size:
        return np.full(n, thr)
    alive = r[r * thr > now]
    return thr * rng.choice(alive if alive.size else r.max(keepdims=True), size=n)


def _remaining(fault: str, laws: list[RunToFailure], log_prior: np.ndarray,
               tracks: list[tuple[np.ndarray, ...]], thr: float, now: float,
               cfg: PrognosisConfig, recorded: Duty, planned: Duty | None,
               rng: np.random.Generator) -> np.ndarray:
    """``cfg.n_samples`` draws of the remaining hours [h], shape (N,): each law's share
    its prior times its evidence (:func:`_paris_laws`, :func:`_posterior`; one law: all),
    its draws of (s, u0) from its posterior, each failing at :func:`_failures`'s severity
    (``now``: the last estimate); ``tracks`` the (severity, weight, exposure) the fit sees
    under each law."""
    posts = [_posterior(*t, fault, cfg, law) for t, law in zip(tracks, laws, strict=True)]
    if len(laws) == 1:
        counts = np.array([cfg.n_samples])
    else:
        lp = log_prior + np.array([p[-1] for p in posts])
        pm = np.exp(lp - lp.max())
        counts = rng.multinomial(cfg.n_samples, pm / pm.sum())
    out = []
    for law, t, post, n in zip(laws, tracks, posts, counts, strict=True):
        if n == 0:
            continue
        s, u0 = _draws(post, int(n), rng)
        u_fail, b = transformed(fault, _failures(thr, now, cfg, int(n), rng), law,
                                cfg.severity_floor)
        need = (u_fail - u0) / (b * s) - t[2][-1]  # exposure to come at s = 1
        if planned is None:  # the recorded duty's mean rate: its cycle's phase is unknown
            rec = exposure(fault, recorded, law)[-1] / (np.sum(recorded.minutes) / 60.0)
            out.append(np.where(need > 0, need / rec if rec > 0 else np.inf, 0.0))
        else:
            out.append(hours_for_exposure(need, planned, exposure(fault, planned, law)))
    return np.concatenate(out)


def predict_growth(track: Track, fault: str, alarm_hour: float | None, recorded: Duty,
                   windows_h: np.ndarray, cfg: PrognosisConfig | None = None, *,
                   planned: Duty | None = None, trained: DutyRange | None = None,
                   threshold: float | None = None, seed: int = 0) -> Prognosis:
    """The physics-based prognosis: the fault's growth law, its scale from the track.

    Parameters
    ----------
    track : Track
        The severity estimates since the alarm, n of them.
    fault : str
        The alarm's fault, one of :data:`swgsim.datasets.growth.LAWS`.
    alarm_hour : float or None
        Operating hour of the alarm that named it [h]; None: no alarm (refused).
    recorded : Duty
        The windows' duty since the alarm (:meth:`Duty.from_windows`), W blocks.
    windows_h : ndarray, shape (W,)
        The operating hour of each recorded window [h].
    cfg : PrognosisConfig or None
        None: the defaults.
    planned : Duty or None
        A duty the user declares for the future, repeated from its first block; None: the
        recorded one's mean exposure per hour [choice: the recorded windows' order need
        not be a whole number of the duty's cycles].
    trained : DutyRange or None
        The duty the model was trained on; a planned duty outside it is refused.
    threshold : float or None
        Failure severity [-]; None: ``cfg.threshold(fault)``.
    seed : int
        Seed of the Monte-Carlo draws (same seed, same prognosis).

    Returns
    -------
    Prognosis
        ``method`` "growth"; not valid before ``cfg.min_track_h`` and ``min_estimates``.

    Raises
    ------
    ValueError
        Before any work, in one line naming the key: no alarm, an estimate before the
        alarm, a fault without a growth law, a threshold at or below the current
        severity, a duty malformed or a planned one outside ``trained``, a bad config.
    """
    cfg = (cfg or PrognosisConfig()).check()
    h, y, lo, hi, thr = check_track(track, fault, alarm_hour, threshold, cfg)
    recorded.check("prognosis.recorded")
    wh = np.asarray(windows_h, float)
    if wh.shape != np.shape(recorded.minutes) or np.any(np.diff(wh) <= 0) \
            or not wh[0] <= h[0]:
        raise ValueError(f"prognosis.windows_h must be one increasing hour per recorded "
                         f"window ({np.shape(recorded.minutes)}), the first at or before "
                         f"the first estimate ({h[0]:g} h), got shape {wh.shape}")
    if planned is not None:
        planned.check("prognosis.planned")
        if trained is not None:
            trained.refuse_outside(planned, "prognosis.planned")
    if reason := not_yet_valid(h, cfg, alarm_hour):
        return not_valid(float(h[-1]), fault, "growth", float(y[-1]), thr, reason)
    tf = cfg.to_failure
    w = ((2.0 * Z90) / (hi - lo)) ** 2  # 1/σ² of each estimate
    first = np.arange(y.size)
    if y.size > cfg.max_bins:  # groups of consecutive estimates (PrognosisConfig.max_bins)
        first = np.unique(np.linspace(0, y.size, cfg.max_bins, endpoint=False).astype(int))
    wsum = np.add.reduceat(w, first)

    def binned(v: np.ndarray) -> np.ndarray:
        return np.add.reduceat(w * v, first) / wsum

    yb = binned(y)
    laws, log_prior = _paris_laws(fault, tf, cfg, y, thr, recorded)
    xs = [binned(_track_exposure(fault, h, recorded, wh, law)) for law in laws]
    ls = np.linspace(-cfg.log_scale_span, cfg.log_scale_span, cfg.n_grid)
    rho = residual_correlation(yb, wsum, binned(_track_exposure(fault, h, recorded, wh, tf)),
                               fault, cfg, ls)
    wb = wsum * (1.0 - rho) / (1.0 + rho)  # the effective sample size of an AR(1) error
    remaining = _remaining(fault, laws, log_prior, [(yb, wb, x) for x in xs], thr,
                           float(y[-1]), cfg, recorded, planned, np.random.default_rng(seed))
    return from_samples(float(h[-1]), fault, "growth", float(y[-1]), thr, remaining, cfg,
                        alarm_hour)
