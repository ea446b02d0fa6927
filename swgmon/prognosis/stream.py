"""The prognosis in the monitor's stream: after a gear-fault alarm whose fault has a growth
law, the severity track since the alarm and the time to the failure threshold.

:func:`stream_prognoses` takes a monitored stream (its trace, named alarms and the monitor
that ran it, :func:`swgmon.advisories.stream.monitor_stream`) and, for each such alarm, estimates
the fault's severity on consecutive blocks of ``block_h`` operating hours of windows after
the alarm (:meth:`GearMonitor.inputs <swgmon.assessment.gear_monitor.GearMonitor.inputs>` and
:meth:`DiagnosisModel.estimate <swgmon.assessment.model.DiagnosisModel.estimate>`, the calls
that give an alarm its severity) and every ``every_h`` hours after it predicts the remaining
hours (:func:`.growth.predict_growth`) under the duty the windows recorded
(input speed, acting load ``t_out_mean_nm``, temperature ``temperature_c``) or a planned
duty the user declares. The option is off by default (:class:`StreamPrognosis`): off, the
monitor's outputs are those without it, bit for bit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from swgmon.assessment.gear_monitor import GearMonitor, Trace
from swgmon.assessment.model import DiagnosisModel
from swgmon.detection.normal import Conditions
from swgmon.detection.rule import Alarm
from swgmon.prognosis.growth import Duty, DutyRange, PrognosisConfig, Track, predict_growth
from swgsim.base.typed import check_range
from swgsim.datasets.growth import LAWS, RunToFailure
from swgsim.datasets.schema import TEMPERATURE_RANGE_C
from swgsim.gear.faults import get_fault
from swgsim.gear.thermal import REF_TEMP_C

__all__ = ["DutyBlock", "StreamPrognosis", "StreamPrognoses", "planned_duty",
           "prognosis_line", "stream_prognoses", "trained_duty"]



@dataclass
class DutyBlock:
    """One block of a planned duty (each field required: NaN refused).

    Attributes
    ----------
    minutes : float
        Operating minutes of the block, in (0, 10^6] [min].
    n_in_rpm, t_acting_nm, temp_c : float
        Input speed [rpm], acting load [N m] and grease temperature [°C], within the duty
        the diagnosis model was trained on (:func:`trained_duty`).
    """

    minutes: float = math.nan
    n_in_rpm: float = math.nan
    t_acting_nm: float = math.nan
    temp_c: float = math.nan


@dataclass
class StreamPrognosis:
    """The stream's prognosis option (``prognosis.*`` of ``swgsim-monitor``; not frozen:
    Hydra overrides it).

    Attributes
    ----------
    enabled : bool
        Off (default): no prognosis, the outputs as without the option.
    every_h : float
        Operating hours between prognoses after an alarm, in (0, 1000] [h] (1 h [choice]:
        the issue's "every hour of operation").
    block_h : float
        Operating hours of windows per severity estimate, in (0, 100] [h] (0.25 h
        [choice]: 15 windows of a minute, a quarter of the alarm's naming hour).
    threshold : float or None
        The failure severity [-]; None: the fault's
        (:data:`swgsim.datasets.growth.FAILURE_SEVERITY`, ``config.to_failure``). An alarm
        naming a fault whose severity range ends below it is followed without a
        prediction (each event says why), not refused: one threshold serves every fault.
    planned : list of DutyBlock
        A future duty the user declares, repeated from its first block; empty: the
        recorded duty's mean rate.
    min_track_h, min_estimates, n_samples, n_grid, log_scale_span, lower_scale, \
upper_scale, max_correlation, in_sight_h, max_bins, severity_floor, gauss_newton_steps, \
paris_m_sd, paris_m_points, failure_ratios : float, int, int, int, float, tuple of float, \
tuple of float, float, float, int, float, int, float, int, tuple of float
        The predictor's (:class:`.growth.PrognosisConfig`, its defaults
        and ranges).
    to_failure : RunToFailure
        The growth's constants the gear is taken to follow
        (:class:`swgsim.datasets.growth.RunToFailure`; a life's ``dataset.life.fault.
        to_failure``), the prior of the gear's scale.
    seed : int
        Seed of the Monte-Carlo draws, >= 0.
    max_prognoses : int
        Most prognoses after one alarm (its follow-up's hours over ``every_h``), each
        predicted, kept and reported in a line, in [1, 10^6]: 10,000 [choice] is a
        prognosis an hour (the default ``every_h``) for more than a year of operation
        (8,760 h), and bounds the work: on a 480-window stream 6,200 prognoses took 9.8 s
        and 12,200 26 s (2 shared cores), so 10,000 take some 15-25 s and 10,000 lines of
        the report.
    """

    enabled: bool = False
    every_h: float = 1.0
    block_h: float = 0.25
    threshold: float | None = None
    planned: list[DutyBlock] = field(default_factory=list)
    min_track_h: float = PrognosisConfig.min_track_h
    min_estimates: int = PrognosisConfig.min_estimates
    n_samples: int = PrognosisConfig.n_samples
    n_grid: int = PrognosisConfig.n_grid
    log_scale_span: float = PrognosisConfig.log_scale_span
    lower_scale: tuple[float, ...] = PrognosisConfig.lower_scale
    upper_scale: tuple[float, ...] = PrognosisConfig.upper_scale
    max_correlation: float = PrognosisConfig.max_correlation
    in_sight_h: float = PrognosisConfig.in_sight_h
    max_bins: int = PrognosisConfig.max_bins
    severity_floor: float = PrognosisConfig.severity_floor
    gauss_newton_steps: int = PrognosisConfig.gauss_newton_steps
    paris_m_sd: float = PrognosisConfig.paris_m_sd
    paris_m_points: int = PrognosisConfig.paris_m_points
    failure_ratios: tuple[float, ...] = PrognosisConfig.failure_ratios
    to_failure: RunToFailure = field(default_factory=RunToFailure)
    seed: int = 0
    max_prognoses: int = 10_000

    @property
    def config(self) -> PrognosisConfig:
        """The predictor's config of these fields."""
        return PrognosisConfig(**{f.name: getattr(self, f.name)
                                  for f in dataclasses.fields(PrognosisConfig)})

    def check(self, where: str = "prognosis", trained: DutyRange | None = None,
              interval_h: float | None = None, span_h: float | None = None
              ) -> StreamPrognosis:
        """Refuse a field out of range, or a planned duty outside ``trained``, in one line
        naming ``<where>.<field>``; return self.

        The number of prognoses is the hours after an alarm over ``every_h``, each kept
        and reported: with the stream's window interval given, ``every_h`` below it is
        refused (between two windows nothing new is known), so that an alarm gets at most
        a prognosis per window, never millions (a 2-h follow-up at 1e-9 h filled 18 GB);
        with the stream's hours after its earliest possible alarm given, ``every_h`` that
        makes more than :attr:`max_prognoses` of them is refused (the window interval is a
        median: a stream whose last window lies 100 h after the others, at one a minute,
        made 6,200).

        Parameters
        ----------
        where : str
            Full name of the option for messages (``prognosis``,
            ``prognosis.study.prognosis``).
        trained : DutyRange, optional
            The duty the diagnosis model was trained on (:func:`trained_duty`); given, a
            planned duty outside it is refused.
        interval_h : float, optional
            The stream's window interval [h] (:func:`window_interval_h`); given, the
            lower bound of ``every_h``.
        span_h : float, optional
            The operating hours an alarm may be followed for, from the earliest possible
            alarm (the first window after commissioning) to the stream's last window [h];
            given, ``every_h`` is bounded below by ``span_h / max_prognoses``.

        Returns
        -------
        StreamPrognosis
            ``self``.

        Raises
        ------
        ValueError
            A field outside its range (the attributes above), ``every_h`` below the
            window interval or making more than :attr:`max_prognoses` prognoses over
            ``span_h``, or the planned duty outside ``trained``
            (``<where>.planned.<quantity>``).
        """
        check_range(self.every_h, 0.0, 1000.0, f"{where}.every_h", "h", lo_open=True)
        check_range(self.max_prognoses, 1, 10**6, f"{where}.max_prognoses")
        most = self.max_prognoses
        if interval_h is not None and self.every_h < interval_h:
            check_range(self.every_h, interval_h, 1000.0, f"{where}.every_h", "h",
                        why=f"at most a prognosis per window: the stream's windows are "
                            f"{60 * interval_h:.3g} min apart")
        if span_h is not None and (n := span_h / self.every_h) > most:
            raise ValueError(f"{where}.every_h={self.every_h:g} h makes {n:.3g} prognoses "
                             f"over the {span_h:.4g} h after the earliest alarm; allowed: at "
                             f"most {most:,} an alarm (every_h from "
                             f"{span_h / most:.3g} h; {where}.max_prognoses)")
        check_range(self.block_h, 0.0, 100.0, f"{where}.block_h", "h", lo_open=True)
        if self.threshold is not None:
            check_range(self.threshold, 0.0, 10.0, f"{where}.threshold", lo_open=True)
        check_range(self.seed, 0, 2 ** 32 - 1, f"{where}.seed")
        self.config.check(where)
        duty = planned_duty(self)
        if duty is not None:
            duty.check(f"{where}.planned")
            if trained is not None:
                trained.refuse_outside(duty, f"{where}.planned")
        return self


def window_interval_h(hours: np.ndarray) -> float | None:
    """The stream's window interval [h]: the median step between its windows' hours; None
    for fewer than two windows."""
    h = np.asarray(hours, float)
    return float(np.median(np.diff(h))) if h.size > 1 else None


def planned_duty(cfg: StreamPrognosis) -> Duty | None:
    """The planned duty of ``cfg`` as a :class:`~.growth.Duty`, K blocks;
    None where none is declared."""
    if not cfg.planned:
        return None
    a = np.array([[b.minutes, b.n_in_rpm, b.t_acting_nm, b.temp_c] for b in cfg.planned],
                 float)
    return Duty(a[:, 0], a[:, 1], a[:, 2], a[:, 3])


def trained_duty(model: DiagnosisModel) -> DutyRange | None:
    """The duty range of a diagnosis model.

    Parameters
    ----------
    model : DiagnosisModel
        Its ``points_range`` (shape (2, 2): speed [rpm] and torque [N m], low and high)
        or None.

    Returns
    -------
    DutyRange or None
        Its operating points' speed and load and the data sets' temperature range
        (:data:`swgsim.datasets.schema.TEMPERATURE_RANGE_C` [°C]; a model records none);
        None where the model records no points.
    """
    pr = getattr(model, "points_range", None)
    if pr is None:
        return None
    pr = np.abs(np.asarray(pr, float))
    return DutyRange((float(pr[:, 0].min()), float(pr[:, 0].max())),
                     (float(pr[:, 1].min()), float(pr[:, 1].max())),
                     tuple(map(float, TEMPERATURE_RANGE_C)))


@dataclass
class StreamPrognoses:
    """The prognoses of a stream.

    Attributes
    ----------
    events : list of dict
        One per prognosis: ``hour``, ``fault``, ``alarm_h`` (the operating hour of the
        alarm it follows [h]), ``valid``, ``reason``, ``severity`` (the
        last estimate), ``threshold``, ``remaining_h`` (median), ``remaining_h_q05``,
        ``remaining_h_q95`` (from ``hour``) and ``failure_h`` (median), ``failure_h_q05``,
        ``failure_h_q95`` (operating hours) [h]; None where not valid or no failure in
        sight (``in_sight_h``).
    tracks : list of dict
        Per alarm followed: ``fault``, ``alarm_h`` and its estimates ``hours``,
        ``severity``, ``lo``, ``hi`` (lists, the 90 % interval).
    readers : list of StreamPrognoses
        The same alarms followed by each of :func:`stream_prognoses`'s ``readers`` (the
        model with other severity regressors), their intervals uncalibrated; empty
        without.
    """

    events: list[dict]
    tracks: list[dict]
    readers: list[StreamPrognoses] = field(default_factory=list)

    def report_lines(self) -> list[str]:
        """One line per valid prognosis (for ``report.md``, :func:`prognosis_line`) and
        the figure's; none where no alarm was followed (no figure then)."""
        if not self.tracks:
            return []
        return [f"- {prognosis_line(e)}" for e in self.events if e["valid"]] + [
            "", "![prognosis](prognosis.png)"]


    def of_track(self, track: dict) -> list[dict]:
        """The events of the alarm a track of :attr:`tracks` follows (its ``fault`` and
        ``alarm_h``; another alarm of the same fault keeps its own), in hour order."""
        return [e for e in self.events
                if e["fault"] == track["fault"] and e["alarm_h"] == track["alarm_h"]]


def prognosis_line(event: dict) -> str:
    """One line saying what a prognosis of :attr:`StreamPrognoses.events` is: e.g.
    ``prognosis at 7.00 h: wear reaches severity 0.8 in 1.20 h [0.90 h, 1.60 h] (5-95 %)``,
    or ``prognosis at 5.00 h: wear: prognosis not yet valid: ...``."""
    e = event
    if not e["valid"]:
        return f"prognosis at {e['hour']:.2f} h: {e['fault']}: {e['reason']}"
    return (f"prognosis at {e['hour']:.2f} h: {e['fault']} reaches severity "
            f"{e['threshold']:.3g} in {_h(e['remaining_h'])} [{_h(e['remaining_h_q05'])}, "
            f"{_h(e['remaining_h_q95'])}] (5-95 %)")


def _h(x: float | None) -> str:
    return "no failure in sight" if x is None else f"{x:.2f} h"


def _num(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def stream_prognoses(tr: Trace, alarms: list[Alarm], mon: GearMonitor, feats: np.ndarray,
                     points: np.ndarray, cond: Conditions, cfg: StreamPrognosis,
                     readers: Sequence[DiagnosisModel] = ()) -> StreamPrognoses:
    """The prognoses after each gear-fault alarm whose fault has a growth law.

    Parameters
    ----------
    tr : Trace
        The monitored windows, n of them.
    alarms : list of Alarm
        The named alarms (:attr:`swgmon.advisories.report.StreamResult.alarms`).
    mon : GearMonitor
        The monitor that ran them (its normal behaviour gives the estimates' inputs).
    feats, points : ndarray, shape (n, F) and (n, 2)
        The windows' health features and operating points (speed [rpm], torque [N m]).
    cond : Conditions
        The windows' conditions (acting load, temperature where read).
    cfg : StreamPrognosis
        The option (checked by the caller).
    readers : sequence of DiagnosisModel
        The model with other severity regressors (the folds' of a cross-validation,
        :meth:`~swgmon.assessment.model.DiagnosisModel.without`): each follows the same
        alarms, its interval with factors 1 (:attr:`StreamPrognoses.readers`).

    Returns
    -------
    StreamPrognoses
        Empty where no alarm's fault has a growth law or the model has no severity
        regressor for it.
    """
    grown = {f for fs in LAWS.values() for f in fs}
    raw = dataclasses.replace(cfg, lower_scale=(1.0,), upper_scale=(1.0,))
    out = StreamPrognoses([], [], [StreamPrognoses([], []) for _ in readers])
    for al in alarms:
        if al.kind == "gear_fault" and al.fault in grown and al.fault in mon.model.severity:
            _follow(tr, al, mon, mon.model, feats, points, cond, cfg, out)
            for model, o in zip(readers, out.readers, strict=True):
                _follow(tr, al, mon, model, feats, points, cond, raw, o)
    return out


def _follow(tr, al, mon, model, feats, points, cond, cfg, out) -> None:
    """Append the track and prognoses of one alarm, its severity read by ``model``, to
    ``out`` (:func:`stream_prognoses`)."""
    idx = np.arange(al.index, tr.hour.size)
    hours = tr.hour[idx]
    block = np.floor((hours - al.hour) / cfg.block_h).astype(int)
    # every window read at once (one regressor call, not one a block: issue 85's time)
    read = model.reads(al.fault, mon.inputs(feats[idx], points[idx], cond[idx],
                                            tr.friction[idx]))
    est = [(float(hours[block == b][-1]), *model.estimate(al.fault, read[block == b]))
           for b in np.unique(block)]
    h, y, lo, hi = np.array(est, float).T
    out.tracks.append({"fault": al.fault, "alarm_h": al.hour, "hours": h.tolist(),
                       "severity": y.tolist(), "lo": lo.tolist(), "hi": hi.tolist()})
    # a window without a reading at the viscosity's reference, where the growth's film
    # factor is 1 (:func:`swgsim.datasets.growth.film_factor`) [choice]
    temp = (np.full(hours.size, REF_TEMP_C) if cond.temperature_c is None else
            np.where(np.isfinite(cond.temperature_c[idx]), cond.temperature_c[idx],
                     REF_TEMP_C))
    thr = cfg.threshold if cfg.threshold is not None else cfg.config.threshold(al.fault)
    planned = planned_duty(cfg)
    for k in range(1, int((hours[-1] - al.hour) / cfg.every_h) + 1):
        now = al.hour + k * cfg.every_h
        n, m = int(np.searchsorted(h, now, side="right")), int(np.searchsorted(
            hours, now, side="right"))
        ev = {"hour": now, "fault": al.fault, "alarm_h": al.hour, "valid": False,
              "severity": None, "threshold": thr}
        if n == 0:
            ev["reason"] = "prognosis not yet valid: no severity estimate since the alarm"
        elif y[n - 1] >= thr:
            ev.update(severity=float(y[n - 1]), reason="the severity estimate has reached "
                      "the failure threshold")
        elif thr > (top := get_fault(al.fault).severity_range[1]):
            ev.update(severity=float(y[n - 1]), reason=f"the failure severity {thr:g} lies "
                      f"beyond {al.fault}'s range (up to {top:g}): not predicted")
        else:
            duty = Duty.from_windows(hours[:m], np.abs(points[idx[:m], 0]),
                                     cond.torque_nm[idx[:m]], temp[:m])
            p = predict_growth(Track(h[:n], y[:n], lo[:n], hi[:n]), al.fault, al.hour,
                               duty, hours[:m], cfg.config, planned=planned, threshold=thr,
                               seed=cfg.seed)
            ev.update(valid=p.valid, reason=p.reason, severity=p.severity_now)
            if p.valid:  # from the last estimate's hour to the prognosis's
                for q, f in (("", p.failure_hour_median), ("_q05", p.failure_hour_q05),
                             ("_q95", p.failure_hour_q95)):
                    ev.update({f"failure_h{q}": _num(f),
                               f"remaining_h{q}": _num(max(f - now, 0.0))})
        for key in ("remaining_h", "remaining_h_q05", "remaining_h_q95", "failure_h",
                    "failure_h_q05", "failure_h_q95"):
            ev.setdefault(key, None)
        out.events.append(ev)

