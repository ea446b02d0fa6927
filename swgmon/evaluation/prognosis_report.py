"""Tables, targets and the figure of the prognosis's evaluation
(:mod:`.prognosis_evaluation`; ``swgsim-train experiment=prognosis``), every
figure computed from the results (:mod:`swgmon.prognosis.scores`), none written in.

The targets (issue 85, in place of issue 47's, which a calibrated interval met in all 18
buckets with probability 0.0014), per data set and fault on the held-out instances: the 90 %
interval's pooled coverage (PICP) with a 95 % interval from a bootstrap over whole lives
that contains 0.90; in every true remaining-share bucket with at least 20 prognoses,
coverage at least 0.85 at 95 % confidence, one-sided (the bootstrap's upper one-sided
95 % bound at or above 0.85); the interval's median width over the true remaining life
beside them; the relative accuracy at half the way from the first prognosis to failure
(its median over lives) >= 0.7; the law's median absolute error at half-life below both
baselines' (linear, Wiener); after a payload change, the predicted failure moves the way
the growth law says within 24 h of operation in every life judged (against its twin
without the change). The alpha-lambda share (alpha 0.2, lambda 0.5) is reported, not a
target.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from swgmon.evaluation.statistics import Interval, life_bootstrap
from swgmon.prognosis.scores import (
    alpha_lambda,
    at_lambda,
    interval_hit,
    phm08_score,
    prognostic_horizon,
    relative_accuracy,
    remaining_fraction,
    share_bucket_label,
    share_buckets,
)
from swgsim.base.lazy import lazy_module
from swgsim.base.markdown import md_table
from swgsim.base.typed import allowed
from swgsim.files.ownership import save_figure, write_owned

pd = lazy_module("pandas")

#: Columns naming a life.
LIFE = ["dataset", "held_out_gear", "seed", "fault"]
#: ``changes.csv``'s columns (:func:`.prognosis_evaluation.prognosis_lives`).
CHANGE_COLUMNS = [*LIFE, "payload", "method", "change_h", "failure_h", "twin_failure_h",
                  "paired", "moved", "lag_h"]


@dataclass
class PrognosisTargets:
    """The prognosis's targets and the scores' parameters (issue 85; declared in
    docs/results/prognosis_protocol.md), ``prognosis.study.targets``, logged with the
    run; the nominal coverage is the study's ``coverage``.

    Attributes
    ----------
    bucket_min : float
        Least coverage of a true remaining-share bucket at ``level`` one-sided confidence,
        in (0, 1) (0.85).
    min_bucket : int
        Least prognoses in a bucket for it to be judged, in [1, 10^6] (20).
    ra_min : float
        Least median relative accuracy at half-life, in [0, 1] (0.7).
    alpha : float
        α of the alpha-lambda score and the prognostic horizon, in (0, 1) (0.2; Saxena et
        al., Int. J. Prognostics and Health Management 1(1), 2010; issue 47).
    lambda_share : float
        λ: the share of the way from the first prognosis to failure at which the scores
        are judged, in (0, 1) (0.5: half-life).
    within_h : float
        Hours of operation after a payload change within which the predicted failure must
        have moved, in (0, 10^4] [h] (24; issue 47).
    share_buckets : int
        Equal buckets of the true remaining share the coverage is judged in, and
        calibrated in (:func:`~.prognosis_evaluation.calibrate`), in [1, 20] (4 [choice]:
        quarters, issue 85).
    level : float
        Confidence level l of the pooled coverage's two-sided interval and of a bucket's
        one-sided bound (the two-sided interval at 2 l − 1's upper end), in (0.5, 1)
        (0.95, issue 85).
    """

    bucket_min: float = field(default=0.85, metadata=allowed(0.0, 1.0, lo_open=True,
                                                             hi_open=True))
    min_bucket: int = field(default=20, metadata=allowed(1, 10**6))
    ra_min: float = field(default=0.7, metadata=allowed(0.0, 1.0))
    alpha: float = field(default=0.2, metadata=allowed(0.0, 1.0, lo_open=True, hi_open=True))
    lambda_share: float = field(default=0.5, metadata=allowed(0.0, 1.0, lo_open=True,
                                                              hi_open=True))
    within_h: float = field(default=24.0, metadata=allowed(0.0, 1e4, lo_open=True, unit="h"))
    share_buckets: int = field(default=4, metadata=allowed(1, 20))
    level: float = field(default=0.95, metadata=allowed(0.5, 1.0, lo_open=True, hi_open=True))


def bucket_table(rows: pd.DataFrame, goal: PrognosisTargets) -> pd.DataFrame:
    """Coverage and width of the 90 % interval per data set, fault, method and remaining-share
    bucket of the remaining-life fraction (``goal.share_buckets`` equal ones,
    :func:`~swgmon.prognosis.scores.share_buckets`, from the alarm to the failure).

    Parameters
    ----------
    rows : DataFrame
        ``results.csv``: one row per prognosis and method.
    goal : PrognosisTargets
        Its ``share_buckets`` and ``level``.

    Returns
    -------
    DataFrame
        ``dataset``, ``fault``, ``method``, ``bucket``, ``n`` (valid prognoses), ``picp``,
        ``picp_low``, ``picp_high`` (its interval at ``goal.level`` from a bootstrap over
        whole lives, ``picp_upper`` the one-sided bound at it:
        a life's prognoses share windows, :func:`~.statistics.
        life_bootstrap`), ``lives``, ``mean_width_h`` (inf where an interval is open),
        ``open`` (share of open intervals), ``phm08`` (mean score of the medians).
    """
    v = rows[rows.valid].copy()
    v["bucket"] = share_bucket_label(remaining_fraction(v.hour, v.alarm_h, v.failure_h),
                                     goal.share_buckets)
    v["hit"] = interval_hit(v.true_remaining_h.to_numpy(), v.remaining_h_q05.to_numpy(),
                            v.remaining_h_q95.to_numpy())
    v["width"] = v.remaining_h_q95 - v.remaining_h_q05
    v["rel_width"] = v.width / v.true_remaining_h
    v["phm08"] = phm08_score(v.true_remaining_h.to_numpy(), v.remaining_h.to_numpy())
    out = []
    for keys, by in (("bucket", ["dataset", "fault", "method", "bucket"]),
                     ("all", ["dataset", "fault", "method"])):
        g = v.groupby(by, sort=True)
        t = g.agg(n=("hit", "size"), picp=("hit", "mean"), mean_width_h=("width", "mean"),
                  median_width_share=("rel_width", "median"),
                  open=("width", lambda w: float(np.mean(~np.isfinite(w)))),
                  phm08=("phm08", "mean")).reset_index()
        if keys == "all":
            t.insert(3, "bucket", "all")
        ci = [_picp_interval(b, goal.level) for _, b in g]
        one = [_picp_interval(b, 2.0 * goal.level - 1.0) for _, b in g]
        t.insert(t.columns.get_loc("picp") + 1, "picp_low", [c.low for c in ci])
        t.insert(t.columns.get_loc("picp") + 2, "picp_high", [c.high for c in ci])
        t.insert(t.columns.get_loc("picp") + 3, "picp_upper", [c.high for c in one])
        t.insert(t.columns.get_loc("picp") + 4, "lives", [c.n for c in ci])
        out.append(t)
    return pd.concat(out, ignore_index=True)


def _picp_interval(b: pd.DataFrame, level: float) -> Interval:
    """A bucket's coverage, its prognoses pooled, with the bootstrap over its lives at
    ``level`` (two-sided)."""
    per = b.groupby(LIFE, sort=False).hit.agg(["sum", "size"])
    return life_bootstrap(per["sum"].to_numpy(float), per["size"].to_numpy(float),
                          level=level)


def life_scores(rows: pd.DataFrame, lives: pd.DataFrame, goal: PrognosisTargets
                ) -> pd.DataFrame:
    """Each life's scores per method: at half-life (``goal.lambda_share`` of the way from
    the method's first valid prognosis to failure,
    :func:`~swgmon.prognosis.scores.at_lambda`) the relative accuracy, the absolute error
    and the alpha-lambda criterion, and the prognostic horizon over all its prognoses.

    Parameters
    ----------
    rows : DataFrame
        ``results.csv``.
    lives : DataFrame
        ``lives.csv``: one row per life.
    goal : PrognosisTargets
        α and λ.

    Returns
    -------
    DataFrame
        One row per life with a failure and method: :data:`LIFE`, ``method``,
        ``followed`` (a prognosis at half-life), ``ra``, ``abs_error_h``,
        ``alpha_lambda`` (False where none), ``horizon_h``, ``horizon_share`` (of the
        span from the first prognosis to failure).
    """
    out = []
    methods = sorted(rows.method.unique()) if len(rows) else []
    for life in lives[np.isfinite(lives.failure_h)].itertuples(index=False):
        mine = rows[(rows[LIFE] == [getattr(life, k) for k in LIFE]).all(axis=1) & rows.valid]
        for m in methods:
            r = mine[mine.method == m].sort_values("hour")
            key = {k: getattr(life, k) for k in LIFE}
            i = at_lambda(r.hour.to_numpy(), life.failure_h, goal.lambda_share)
            if i is None or i < 0:
                out.append({**key, "method": m, "followed": False, "ra": np.nan,
                            "abs_error_h": np.nan, "alpha_lambda": False, "horizon_h": 0.0,
                            "horizon_share": 0.0})
                continue
            t, p = r.true_remaining_h.to_numpy(), r.remaining_h.to_numpy()
            ph = prognostic_horizon(r.hour.to_numpy(), t, p, life.failure_h, goal.alpha)
            out.append({**key, "method": m, "followed": True,
                        "ra": float(relative_accuracy(t[i:i + 1], p[i:i + 1])[0]),
                        "abs_error_h": float(abs(p[i] - t[i])),
                        "alpha_lambda": bool(alpha_lambda(t[i:i + 1], p[i:i + 1],
                                                          goal.alpha)[0]),
                        "horizon_h": ph, "horizon_share": ph / (life.failure_h - r.hour.iloc[0])})
    return pd.DataFrame(out)


def change_table(changes: pd.DataFrame, goal: PrognosisTargets) -> pd.DataFrame:
    """Per data set, fault and method, the lives with a payload change: how many, how
    many were judged (a paired prognosis after the change), the share of judged ones whose
    predicted failure moved the law's way within ``goal.within_h`` and the median lag.

    Parameters
    ----------
    changes : DataFrame
        ``changes.csv`` (:data:`CHANGE_COLUMNS`).
    goal : PrognosisTargets
        The hours within which it must have moved.

    Returns
    -------
    DataFrame
        ``dataset``, ``fault``, ``method``, ``lives``, ``judged``, ``moved_share`` (NaN
        where none judged), ``lag_median_h``.
    """
    c = changes.assign(judged=changes.moved.notna(),
                       ok=changes.moved.eq(True) & (changes.lag_h <= goal.within_h))
    g = c.groupby(["dataset", "fault", "method"], sort=True)
    out = g.agg(lives=("judged", "size"), judged=("judged", "sum"), ok=("ok", "sum"),
                lag_median_h=("lag_h", "median")).reset_index()
    out.insert(5, "moved_share", out.ok / out.judged.where(out.judged > 0))
    return out.drop(columns="ok")


def summary_table(scores: pd.DataFrame) -> pd.DataFrame:
    """Per data set, fault and method: lives, lives followed to half-life, the median
    relative accuracy and absolute error at half-life over the followed lives, the share
    of all lives meeting alpha-lambda, the median prognostic horizon and its share."""
    g = scores.groupby(["dataset", "fault", "method"], sort=True)
    return g.agg(lives=("followed", "size"), followed=("followed", "sum"),
                 ra_median=("ra", "median"), abs_error_median_h=("abs_error_h", "median"),
                 alpha_lambda_share=("alpha_lambda", "mean"),
                 horizon_median_h=("horizon_h", "median"),
                 horizon_share_median=("horizon_share", "median")).reset_index()


def targets(buckets: pd.DataFrame, summary: pd.DataFrame, moved: pd.DataFrame,
            goal: PrognosisTargets, nominal: float) -> pd.DataFrame:
    """The issue's targets for the growth law per data set and fault, each with its
    measured value and pass or fail (module docstring; ``goal``'s thresholds, the
    interval's ``nominal`` coverage); a bucket with fewer than ``goal.min_bucket``
    prognoses, and a fault without a judged payload change (:func:`change_table`), are
    listed as not judged."""
    out = []

    def row(ds, fault, what, target, measured, result):
        out.append({"dataset": ds, "fault": fault, "what": what, "target": target,
                    "measured": measured, "result": result})

    for b in buckets[buckets.method == "growth"].itertuples(index=False):
        width = f"; median width {b.median_width_share:.2f} of the true remaining life"
        if b.bucket == "all":
            ok = b.picp_low <= nominal <= b.picp_high
            row(b.dataset, b.fault, f"pooled PICP of the 90 % interval ({b.n} prognoses, "
                f"{b.lives} lives){width}", f"{goal.level:.0%} interval holds {nominal:g}",
                f"{b.picp:.2f} [{b.picp_low:.2f}, {b.picp_high:.2f}]",
                "pass" if ok else "fail")
            continue
        judged = b.n >= goal.min_bucket
        row(b.dataset, b.fault, f"PICP, true bucket {b.bucket} ({b.n} prognoses){width}",
            f">= {goal.bucket_min:g} at {goal.level:.0%} (one-sided)",
            f"{b.picp:.2f} (upper bound {b.picp_upper:.2f})",
            ("pass" if b.picp_upper >= goal.bucket_min else "fail") if judged
            else f"not judged (< {goal.min_bucket})")
    for (ds, fault), s in summary.groupby(["dataset", "fault"]):
        if not (s.method == "growth").any():
            continue
        gr = s[s.method == "growth"].iloc[0]
        row(ds, fault, "relative accuracy at half-life (median over lives)",
            f">= {goal.ra_min:g}", f"{gr.ra_median:.3g}",
            "pass" if gr.ra_median >= goal.ra_min else "fail")
        for b in s[s.method != "growth"].itertuples(index=False):
            ratio = gr.abs_error_median_h / b.abs_error_median_h
            row(ds, fault, f"median abs error at half-life / {b.method}'s", "< 1",
                f"{ratio:.3g}", "pass" if ratio < 1 else "fail")
    for m in moved[moved.method == "growth"].itertuples(index=False):
        row(m.dataset, m.fault, f"after a payload change the predicted failure moves the "
            f"law's way within {goal.within_h:g} h ({m.judged} of {m.lives} lives judged)",
            "every life", f"{m.moved_share:.2f}",
            ("pass" if m.moved_share == 1.0 else "fail") if m.judged
            else "not judged (no paired prognosis)")
    return pd.DataFrame(out, columns=["dataset", "fault", "what", "target", "measured",
                                      "result"])


def write_table(path: Path, header: str, tgt: pd.DataFrame, summary: pd.DataFrame,
                buckets: pd.DataFrame, lives: pd.DataFrame, calibration: pd.DataFrame,
                moved: pd.DataFrame) -> None:
    """``table.md``: the header, the targets with pass or fail, the scores per fault and
    method, the coverage per remaining-share bucket, the payload changes (:func:`change_table`),
    the lives and the calibration."""
    lv = lives.assign(after_onset_h=lives.failure_h - lives.onset_h,
                      alarm_after_onset_h=lives.alarm_h - lives.onset_h)
    alarms = lv.groupby(["dataset", "fault"]).agg(
        lives=("seed", "size"), failed=("failure_h", lambda f: int(np.isfinite(f).sum())),
        followed=("alarm_h", lambda a: int(np.isfinite(a).sum())),
        median_failure_after_onset_h=("after_onset_h", "median"),
        median_alarm_after_onset_h=("alarm_after_onset_h", "median")).reset_index()
    text = header + "".join(
        f"\n## {title}\n\n{md_table(t.columns, t.itertuples(index=False))}\n" for title, t in (
            ("Targets (the growth law)", tgt),
            ("Scores per fault and method (held-out instances)", summary),
            ("The 90 % interval per remaining-share bucket (remaining share of the way from the "
             "alarm to failure)", buckets),
            ("After a payload change, against the same life without it", moved),
            ("Lives", alarms),
            ("Calibration (conformal over the training instances' lives)", calibration))
    ) + "\n![prognosis](prognosis.png)\n"
    write_owned(path, lambda tmp: Path(tmp).write_text(text))


def figure(buckets: pd.DataFrame, rows: pd.DataFrame, path: Path, goal: PrognosisTargets,
           nominal: float) -> Path:
    """``prognosis.png``: the 90 % interval's coverage per remaining-share bucket and method (all
    faults and data sets pooled; the ``nominal`` coverage and ``goal.bucket_min`` drawn),
    and the predicted against the true remaining hours of every valid prognosis per method
    (median)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    v = rows[rows.valid].copy()
    v["bucket"] = share_bucket_label(remaining_fraction(v.hour, v.alarm_h, v.failure_h),
                                     goal.share_buckets)
    v["hit"] = interval_hit(v.true_remaining_h.to_numpy(), v.remaining_h_q05.to_numpy(),
                            v.remaining_h_q95.to_numpy())
    labels = share_buckets(goal.share_buckets)
    methods = sorted(v.method.unique())
    for k, m in enumerate(methods):
        cov = v[v.method == m].groupby("bucket").hit.mean().reindex(labels)
        ax[0].bar(np.arange(len(labels)) + 0.25 * (k - 1), cov.to_numpy(), 0.25, label=m)
        r = v[(v.method == m) & np.isfinite(v.remaining_h) & (v.remaining_h > 0)]
        ax[1].loglog(r.true_remaining_h, r.remaining_h, ".", ms=3, alpha=0.5, label=m)
    ax[0].axhline(nominal, color="k", lw=1, label=f"nominal {nominal:g}")
    ax[0].axhline(goal.bucket_min, color="0.5", lw=1, ls="--",
                  label=f"least {goal.bucket_min:g}")
    ax[0].set(xticks=range(len(labels)), xticklabels=labels, ylim=(0, 1.05),
              xlabel="remaining share of the way from alarm to failure",
              ylabel="coverage of the 90 % interval (PICP)")
    lim = [max(v.true_remaining_h.min(), 1e-2), v.true_remaining_h.max()] if len(v) else [1, 2]
    ax[1].loglog(lim, lim, "k-", lw=1)
    ax[1].set(xlabel="true remaining hours [h]", ylabel="predicted (median) [h]")
    for a in ax:
        a.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, 110)


__all__ = ["PrognosisTargets", "bucket_table", "figure", "life_scores", "summary_table",
           "targets", "write_table"]
