"""scripts/results_pages.py: the monitor's real-day and timing blocks, built from a
hand-made run's reports whose figures are known, written between their markers only."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import results_pages  # noqa: E402


def _run(tmp: Path) -> Path:
    """A monitor run of one data set, two held-out gears, stationary and under 'hall':
    gear 2 had one gear-fault alarm, one alarm naming a sensor fault of one bridge and two
    advisories in 200 h under the hall; its mild
    eccentric WG under the hall was missed."""
    fa, res = [], []
    for n in ("none", "hall"):
        for g in (1, 2):
            key = {"dataset": "bench", "held_out_gear": g, "seed": 0, "nuisance": n,
                   "output_encoder": False}
            bad = n == "hall" and g == 2
            fa.append({**key, "detector": "monitor", "healthy_hours": 200.0,
                       "false_alarms": 2 * int(bad), "gear_fault_alarms": int(bad),
                       "sensor_fault_alarms": int(bad), "unexplained_changes": 0,
                       "advisories": 2 * int(bad)})
            for sev in (0.05, 0.2):
                miss = bad and sev == 0.05
                res.append({**key, "detector": "monitor", "fault": "eccentric_wg",
                            "severity": sev, "onset": "step", "detected": not miss,
                            "time_to_detect_h": float("nan") if miss else 0.2,
                            "fault_after_1h": "" if miss else "eccentric_wg"})
    out = tmp / "reports" / "monitor"
    out.mkdir(parents=True)
    pd.DataFrame(res).to_csv(out / "results.csv", index=False)
    pd.DataFrame(fa).to_csv(out / "false_alarms.csv", index=False)
    parts = [{"dataset": "bench", "held_out_gear": g, "detector": d, "train_s": 60.0,
              "evaluate_s": 240.0} for g in (1, 2) for d in (None, "paper_rf")]
    (out / "timing.json").write_text(json.dumps({"wall_s": 900.0, "parts": parts}))
    return out.parent


def test_the_monitor_blocks_hold_the_runs_figures(tmp_path):
    rep = _run(tmp_path)
    day = results_pages.monitor_real_day(rep)
    assert "| bench | hall | 200 | 0 / 5 | 0 / 10 | 0 / 5 | 0 / 0 | 3 of 3 |" in day
    assert "| bench | none | 200 | 0 / 0 | 0 / 0 | 0 / 0 | 0 / 0 | 4 of 4 |" in day
    assert "| bench | eccentric WG | 0.05 | 2/2, 12 min | 1/2, 12 min |" in day
    timing = results_pages.monitor_timing(rep)
    assert "Wall time **15.0 min**" in timing
    assert "| bench | monitor | 2.0 | 8.0 | 10.0 |" in timing
    assert "| all |  | 4.0 | 16.0 | 20.0 |" in timing
    assert "resumed" not in timing
    t = json.loads((rep / "monitor" / "timing.json").read_text())
    (rep / "monitor" / "timing.json").write_text(json.dumps({**t, "resumed": 3}))
    timing = results_pages.monitor_timing(rep)  # a run that resumed parts timed only its own
    assert "Wall time **15.0 min** (3 of 4 parts resumed from parts/, not timed here)" in timing


def test_only_the_blocks_between_their_markers_change(tmp_path):
    rep = _run(tmp_path)
    pages = tmp_path / "pages"
    shutil.copytree(ROOT / "docs" / "results", pages)
    before = (pages / "monitor.md").read_text(encoding="utf-8")
    assert results_pages.main([str(rep), "--pages", str(pages), "--commit", "abc1234"]) == 0
    after = (pages / "monitor.md").read_text(encoding="utf-8")
    assert "at commit `abc1234`" in after and "0 / 5" in after
    outside = results_pages.BLOCK_RE.sub("", before)
    assert results_pages.BLOCK_RE.sub("", after) == outside
    assert [p.name for p in pages.iterdir() if p.is_file() and p.read_text(encoding="utf-8")
            != (ROOT / "docs" / "results" / p.name).read_text(encoding="utf-8")] == ["monitor.md"]


def test_the_figures_block_shows_and_copies_each_acquisitions_figures(tmp_path):
    """A paper run with two tiny figures, one per acquisition: the block shows both, the
    paper acquisition first, and the run copies them beside the page, nothing else; a
    second run finds nothing to do."""
    rep = tmp_path / "reports"
    for acq, name, data in (("bench", "fig6_signals", b"png-b"),
                            ("paper", "confusion_X", b"png-p")):
        (rep / acq).mkdir(parents=True)
        (rep / acq / f"{name}.png").write_bytes(data)
    block = results_pages.paper_figures(rep)
    assert block.index("**paper acquisition**") < block.index("**bench acquisition**")
    assert "](figures/paper_confusion_X.png)" in block and "Table X" in block
    assert "](figures/bench_fig6_signals.png)" in block and "Fig. 6 analogue" in block
    pages = tmp_path / "pages"
    shutil.copytree(ROOT / "docs" / "results", pages, ignore=shutil.ignore_patterns("*.png"))
    args = [str(rep), "--pages", str(pages), "--commit", "abc1234"]
    assert results_pages.main(args) == 0
    assert sorted(p.name for p in (pages / "figures").iterdir()) == [
        "bench_fig6_signals.png", "paper_confusion_X.png"]
    assert (pages / "figures" / "bench_fig6_signals.png").read_bytes() == b"png-b"
    page = (pages / "paper.md").read_text(encoding="utf-8")
    assert "`swgsim-paper` at commit `abc1234`" in page and "paper_confusion_X.png" in page
    assert results_pages.main([*args, "--check"]) == 0


def test_the_prognosis_blocks_copy_the_tables_of_their_sections(tmp_path):
    """A hand-made prognosis report: each block holds its own section's table, not the
    next one's; the timing block the wall time and each part's seconds."""
    out = tmp_path / "reports" / "prognosis"
    out.mkdir(parents=True)
    (out / "table.md").write_text(
        "# Prognosis\n\nheader\n\n## Targets (the growth law)\n\n| a |\n|---|\n| t1 |\n"
        "\n## Scores per fault and method (held-out gears)\n\n| b |\n|---|\n| s1 |\n"
        "\n## After a payload change, against the same life without it\n\n| c |\n|---|\n"
        "| c1 |\n\n## Lives\n\n| d |\n|---|\n| l1 |\n")
    (out / "timing.json").write_text(json.dumps({"wall_s": 600.0, "parts": [
        {"dataset": "bench", "held_out_gear": None, "train_s": 80.4, "calibrate_s": 100.0,
         "evaluate_s": None}] + [{"dataset": "bench", "held_out_gear": g, "train_s": None,
                                  "calibrate_s": None, "evaluate_s": s}
                                 for g, s in ((9, 60.6), (10, 20.0))]}))
    rep = out.parent
    assert results_pages.prognosis_section("Targets")(rep) == "| a |\n|---|\n| t1 |"
    assert results_pages.prognosis_section("After a payload change")(rep).endswith("| c1 |")
    timing = results_pages.prognosis_timing(rep)
    assert "Wall time **10.0 min**" in timing and "| bench | 80 | 100 | 81 | 61 |" in timing


def test_the_families_block_puts_each_gears_figures_side_by_side(tmp_path):
    """Two held-out gears' tables of scripts/monitor_families.py, written in the wrong
    order: one row per family, each cell gear 1's figure then gear 2's; the wall time of
    a run that recorded it, none of one read again (--read)."""
    rep = tmp_path / "reports"
    for g, alarms, wall in ((2, 6.0, float("nan")), (1, 0.0, 600.0)):
        folder = rep / "monitor_families" / f"bench_g{g}"
        folder.mkdir(parents=True)
        pd.DataFrame([{"family": fam, "dataset": "bench", "held_out_gear": g,
                       "seeds": "0 1 2 3 4", "gear_fault_alarms_per_1000h": alarms,
                       "unexplained_changes_per_1000h": 1.0, "advisories_per_1000h": 5.0,
                       "detected": "70/75", "growing_detected": "20/25",
                       "median_ttd_h": 0.2, "named_right_1h": 0.9,
                       "targets_detected": f"{59 - g}/60", "mildest_step_ttd_h": 0.125,
                       "targets_named_right": 0.8, "sensor_reported_h": sensor,
                       "wall_s": wall}
                      for fam, sensor in (("warm_up", "-"), ("sensor_stuck", "5/5, 0.25"))]
                     ).to_csv(folder / "table.csv", index=False)
    block = results_pages.monitor_families(rep)
    assert "held-out gears 1 / 2" in block and "seeds 0 1 2 3 4" in block
    assert "| `warm_up` | 0 / 6 | 1 / 1 | 5 / 5 | 58/60 / 57/60 | 0.12 / 0.12 | 0.80 / 0.80 " \
           "| - / - |" in block
    assert "| `sensor_stuck` | 0 / 6 |" in block and "| 5/5, 0.25 / 5/5, 0.25 |" in block
    assert "bench gear 1 20.0 min" in block and "gear 2" not in block.split("Wall")[1]


def test_the_benchmark_blocks_judge_the_protocols_targets(tmp_path):
    """The targets block judges every family's six targets and the pooled two from the
    run's rows; the tables block copies each data set's table; the timing block sums the
    lives parts."""
    import numpy as np
    import pandas as pd

    b = tmp_path / "benchmark"
    b.mkdir()
    rows, fa = [], []
    for det in ("monitor", "monitor_generic", "regression_mewma", "pca"):
        for fam in ("warm_up", "all"):
            for i in range(4):
                hit = det == "monitor" or i < 2
                rows.append({"dataset": "bench", "family": fam, "detector": det,
                             "held_out_gear": 9 + i, "fault": "eccentric_wg",
                             "detected": hit, "time_to_detect_h": 3.0 if hit else np.nan,
                             "fault_at_alarm": "eccentric_wg", "fault_after_1h": "root"})
                fa.append({"dataset": "bench", "family": fam, "detector": det,
                           "held_out_gear": 9 + i, "healthy_hours": 176.0,
                           "gear_fault_alarms": 0 if det == "monitor" else 2})
    pd.DataFrame(rows).to_csv(b / "results.csv", index=False)
    pd.DataFrame(fa).to_csv(b / "false_alarms.csv", index=False)
    (b / "table.md").write_text("# Benchmark\n\nintro\n\n## bench, every held-out instance"
                                "\n\n| a |\n|---|\n| 1 |\n")
    (b / "timing.json").write_text(json.dumps({"wall_s": 600.0, "resumed": 0, "parts": [
        {"dataset": "bench", "gear": 9, "family": "all", "wall_s": 300.0},
        {"dataset": "bench", "gear": 10, "family": "all", "wall_s": 100.0}]}))
    block = results_pages.benchmark_targets_block(tmp_path)
    assert "**bench**: 13 of 15 targets met" in block  # named 1 h after missed twice
    assert "6 naming (>= 0.8) |" in block and "0 **missed**" in block
    assert "target 8, against the ablation" in block
    second = results_pages.benchmark_second(tmp_path)
    assert "**bench**: 12 of 14 judged cells met" in second  # F: CADD equal, not below
    assert "- F, against pca: detected, CADD [h]: monitor 1 / 3, bound 0.5 / 3: **missed**" \
        in second
    assert "| warm_up | 4 of 4 | 0 (0.97) | 0 |" in second
    assert "| eccentric_wg | 8 | 1 met | 0 met | 1 met |" in second
    assert "- E, sensor families' healthy lives with a gear-fault alarm: 0 of 0: met" in second
    tables = results_pages.benchmark_tables_block(tmp_path)
    assert tables == "**bench, every held-out instance**\n\n| a |\n|---|\n| 1 |"
    assert "| bench | 2 | 400 | 200 | 300 |" in results_pages.benchmark_timing(tmp_path)
