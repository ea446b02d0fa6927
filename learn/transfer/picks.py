"""Which run a line of the transfer report states: the declared primary first, the best
beside it, marked as chosen afterwards.

The *primary* run (``transfer.primary``, declared before the comparison) is the result of
a data set; the *best* run, the highest worst-split mean on the evaluation windows, is
chosen afterwards and says so (:data:`BEST`). Every line that states "the" result goes
through :func:`picks`. At k > 0 the primary is its first k-shot adaptation in the order of
:data:`PRIMARY_ADAPTATIONS`, or its k = 0 result for a run without one
(``docs/learners_transfer.md``, "What was chosen on what data").
"""

from __future__ import annotations

from collections.abc import Sequence

from learn.studies.protocols import OOD_PROTOCOLS
from learn.studies.runs import RunRef
from learn.transfer.study import FT_MODES
from swgsim.base.lazy import lazy_module
from swgsim.base.markdown import md_table

pd = lazy_module("pandas")

PRIMARY = "primary, declared before the comparison"
BEST = "best, chosen afterwards on the held-out windows"
NO_PRIMARY = "no primary declared"
PRIMARY_NOT_RUN = "the declared primary did not run here"
#: Which adaptation of the primary is its result at k > 0, first found first (fixed
#: before the comparison, never chosen on results).
PRIMARY_ADAPTATIONS = ("ft_head", *(f"ft_{m}" for m in FT_MODES))


def primary_row(w: pd.DataFrame, primary: RunRef | None, k: int) -> pd.Series | None:
    """The primary's worst-split row at ``k`` among one (dataset, protocol)'s worst-split
    rows ``w`` (every k); None when none is declared or it did not run."""
    if primary is None:
        return None
    mine = w[(w["model"].str.partition("+")[0] == primary.model)
             & (w["input"] == primary.input)]
    names = [f"{primary.model}+{a}" for a in PRIMARY_ADAPTATIONS] if k > 0 else []
    for name, kk in [*((n, k) for n in names), (primary.model, 0)]:
        r = mine[(mine["model"] == name) & (mine["k_shot"] == kk)]
        if len(r):
            return r.iloc[0]
    return None


def picks(w: pd.DataFrame, primary: RunRef | None, k: int
          ) -> list[tuple[str, pd.Series | None]]:
    """(who, row) of the primary and the best run at ``k``, primary first.

    ``w``: one (dataset, protocol)'s worst-split rows. The primary's row is None, its
    ``who`` :data:`NO_PRIMARY` or :data:`PRIMARY_NOT_RUN`, when there is none; the best
    is labelled :data:`BEST`. Empty when no run has this k.
    """
    cand = w[w["k_shot"] == int(k)]
    if cand.empty:
        return []
    pr = primary_row(w, primary, k)
    who = NO_PRIMARY if primary is None else PRIMARY if pr is not None else PRIMARY_NOT_RUN
    return [(who, pr), (BEST, cand.loc[cand["mean"].idxmax()])]


def headline_table(summ: pd.DataFrame, primary: RunRef | None) -> pd.DataFrame:
    """Per data set, leave-one-gear-out protocol and k: the primary's worst-split mean
    accuracy and the best run's beside it.

    Parameters
    ----------
    summ : pandas.DataFrame
        :func:`learn.transfer.report.summarise`.
    primary : RunRef, optional
        ``transfer.primary``.

    Returns
    -------
    pandas.DataFrame
        Columns dataset, protocol, k_shot, who, model, input, accuracy (0..1), worst_of;
        the primary's row first.
    """
    w_all = summ[(summ["split"] == "worst") & summ["protocol"].isin(OOD_PROTOCOLS)]
    rows = []
    for (ds, prot), w in w_all.groupby(["dataset", "protocol"], sort=False):
        for k in sorted(set(w["k_shot"].astype(int))):
            for who, r in picks(w, primary, k):
                run = {} if r is None else {"model": r["model"], "input": r["input"],
                                            "accuracy": float(r["mean"]),
                                            "worst_of": r["worst_of"]}
                rows.append({"dataset": ds, "protocol": prot, "k_shot": k, "who": who,
                             **run})
    return pd.DataFrame(rows, columns=["dataset", "protocol", "k_shot", "who", "model",
                                       "input", "accuracy", "worst_of"])


def _cell(r, label, split: bool) -> str:
    """One pick of the headline: accuracy and run, or what is missing."""
    if pd.isna(r.model):
        return r.who
    where = f", {r.worst_of}" if split else ""
    return (f"{100 * r.accuracy:.2f} % ({label(r.model, r.input, int(r.k_shot))}{where}; "
            f"{r.who})")


def headline_lines(head: pd.DataFrame, label) -> list[str]:
    """One line per (data set, protocol, k): the primary's accuracy first, the best
    beside it marked as chosen afterwards. ``label(model, input, k)`` names a run."""
    return [f"{ds} {prot} k = {k}: " + "; beside it ".join(_cell(r, label, False)
                                                           for r in g.itertuples())
            for (ds, prot, k), g in head.groupby(["dataset", "protocol", "k_shot"],
                                                 sort=False)]


def headline_md(head: pd.DataFrame, label, order: Sequence[str]) -> list[str]:
    """The headline section of ``table.md`` (rows of :func:`headline_table`); ``label``
    as for :func:`headline_lines`, ``order``: the data sets."""
    if not len(head):
        return []
    rows = [[f"{ds}", f"{prot}", f"{k}", *(_cell(r, label, True) for r in g.itertuples())]
            for ds in order for (prot, k), g in head[head["dataset"] == ds].groupby(
                ["protocol", "k_shot"], sort=False)]
    return ["## Headline", "",
            "Accuracy on the worst split, mean over seeds. The result of a data set is the "
            "primary run, declared before the comparison; beside it the best run, chosen "
            "afterwards on the held-out gear's evaluation windows (a statement about the "
            "runs compared, not a result one could have chosen in advance).", "",
            md_table(["data set", "protocol", "k", "result (primary)", "beside it (best)"], rows,
                     "llrll"), ""]
