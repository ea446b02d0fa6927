"""Every pair of apps writing into one folder: nothing one app made is lost to another.

The ownership stamp records, per file, the app and the kind of output that wrote it
(:mod:`swgsim.files.writers`). Each app is run, as its task function with its real composed
config, into a folder holding another app's finished output: it refuses in one line naming
a file and its writer, before any work, and the folder stays byte-identical. Generation
replaces only an unfinished data set that a generation run wrote; a stamp of an earlier
version (no writers) is an unknown app's, replaced only by generation with ``overwrite``.

The writers' folders are made once per module: generation and the calibration for real (a
second each; generation's a copy of the session's generated ``small_cfg`` set,
tests/conftest.py); the other apps' through the same claim and atomic writes they use, with the
files they write (a real run of each takes 10-40 s: the slow test at the end runs every one
and checks that its stamp names it, so that the folders made here are what they make).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from bad_input import calibrate_call, friction_csv, small_cfg
from omegaconf import OmegaConf

from swgcli import compose_app
from swgcli.app import one_line
from swgsim.datasets import generate as gen
from swgsim.files import ownership
from swgsim.files.writers import WRITERS

#: App -> the tag it claims its folder with (swgsim.files.writers.WRITERS).
TAGS = {"generate": "swgsim-generate", "calibrate": "swgsim-calibrate",
        "monitor": "swgsim-monitor", "observability": "swgsim-observability",
        "export": "swgsim-export", "paper": "paper-study", "monitor_evaluation": "monitor",
        "transfer": "transfer", "import": "swgsim-import"}
#: The files each app writes (names as the apps write them; several share summary.json,
#: report.md, results.csv or table.md, which is how one app overwrote another's).
OUTPUT = {
    "monitor": ["summary.json", "report.md", "health.png"],
    "observability": ["observability.csv", "torsional_modes.csv", "observability.png"],
    "export": ["swg_monitor.c", "swg_monitor.h", "size.json", "summary.json"],
    "paper": ["results.csv", "confusion.csv", "tables_vii_x.md"],
    "monitor_evaluation": ["results.csv", "table.md", "timing.json", "parts/tiny_g3.json",
                           "models/tiny_without_gear3.skops",
                           "models/tiny_without_gear3.card.json"],
    "transfer": ["results.csv", "table.md", "summary.md"],
    "import": ["gear3_life.nc", "manifest.json"],
}
#: A mapping of a recording (swgsim.datasets.recordings), for swgsim-import's runs.
MAPPING = {"time": "time_s", "clock": {"column": "hours", "unit": "h"},
           "operating_points": {"points": [[4000.0, 7.0]]}, "commissioning_h": 1.0,
           "gear": 3, "window_s": 0.06, "sample_rate_hz": 10000.0, "interval_min": 1.0}
APPS = list(TAGS)


def files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (hidden ones included) and its bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _made_by(tag: str, folder: Path, names: list[str]) -> Path:
    """``folder`` claimed as the app ``tag`` claims it, ``names`` written into it."""
    with ownership.claim(folder, tag, strict=True):
        for n in names:
            (folder / n).parent.mkdir(parents=True, exist_ok=True)
            ownership.atomic_write_bytes(folder / n, f"{tag}: {n}\n".encode())
    return folder


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("pairs")


@pytest.fixture(scope="module")
def csv(root) -> Path:
    t = np.arange(2000) * 0.002
    return friction_csv(root / "rec.csv", t, np.sin(t), np.cos(t),
                        0.1 * np.tanh(20 * np.cos(t)))


@pytest.fixture(scope="module")
def written(root, csv, small) -> dict[str, Path]:
    """App -> a folder holding its finished output (in ``<root>/<app>/bench``, so that the
    main job's study folder ``<report_root>/bench`` can be pointed at it)."""
    out = {}
    for app in APPS:
        folder = root / app / "bench"
        if app == "generate":
            shutil.copytree(small, folder)  # gen.generate(small_cfg(), folder)'s output
        elif app == "calibrate":
            calibrate_call(csv, folder, "figures=false")()
        else:
            _made_by(TAGS[app], folder, OUTPUT[app])
        out[app] = folder
    return out


@pytest.fixture(scope="module")
def runners(root, csv):
    """App -> a call ``run(folder)`` running that app into ``folder`` (its config composed
    once, the folder set per call)."""
    mapping = root / "mapping.json"  # YAML reads JSON
    mapping.write_text(json.dumps(MAPPING))
    from learn.observability.task import run_observability
    from swgcli.calibrate import run_calibrate
    from swgcli.export import run_export_app
    from swgcli.importer import run_import
    from swgcli.paper import run_paper
    from swgcli.tasks import run_train
    from swgmon.advisories.task import run_monitor_app

    def with_dir(cfg, key, task):
        def run(folder: Path):
            c = cfg.copy()
            OmegaConf.update(c, key, str(folder))
            return task(c)
        return run

    train = ["~logger", f"paths.data_dir={root}/none"]
    out = {
        "calibrate": with_dir(compose_app("calibrate", [
            f"measured={csv}", "out_dir=x", "~logger", "figures=false"]),
            "out_dir", run_calibrate),
        "monitor": with_dir(compose_app("monitor", [
            f"stream={root}/none", f"diagnosis_model={root}/none.joblib", "out_dir=x",
            "~logger"]), "out_dir", run_monitor_app),
        "observability": with_dir(compose_app("observability", [
            "dataset=tiny_bench", "j_out_kgm2=[0.0088]", f"data_root={root}/none",
            "report_dir=x", "n_jobs=1", "progress=false"]), "report_dir", run_observability),
        "export": with_dir(compose_app("export", ["dataset=tiny_bench", "out_dir=x",
                                                  "cross=false"]), "out_dir", run_export_app),
        "monitor_evaluation": with_dir(compose_app("train", [
            "experiment=monitor", *train, "monitor.run_on=[bench]", "monitor.report_dir=x"]),
            "monitor.report_dir", run_train),
        "transfer": with_dir(compose_app("train", [
            "experiment=transfer", *train, "transfer.report_dir=x"]),
            "transfer.report_dir", run_train),
        "import": with_dir(compose_app("import", [
            f"recording={root}/none.csv", f"mapping={mapping}", "out_dir=x",
            "progress=false"]), "out_dir", run_import),
    }
    paper = compose_app("paper", ["grid=tiny", "run_on=[bench]", f"data_root={root}/none",
                                  "report_root=x", f"tracking_uri=sqlite:///{root}/m.db"])
    out["paper"] = lambda folder: with_dir(paper, "report_root", run_paper)(folder.parent)
    out["generate"] = lambda folder: gen.generate(small_cfg(), folder, n_jobs=1,
                                                  progress=False)
    out["generate overwrite"] = lambda folder: gen.generate(
        small_cfg(), folder, n_jobs=1, progress=False, overwrite=True)
    return out


def refusal(call) -> str:
    with pytest.raises(ValueError) as info:
        call()
    msg = one_line(info.value)
    assert msg is not None and "\n" not in msg
    return msg


PAIRS = [(w, r) for w in APPS for r in [*APPS, "generate overwrite"]
         if w != r and not (w == "generate" and r == "generate overwrite")]


@pytest.mark.parametrize("writer, runner", PAIRS)
def test_an_app_refuses_another_apps_output_naming_it(written, runners, root, writer, runner):
    folder = written[writer]
    before = files(folder)
    msg = refusal(lambda: runners[runner](folder))
    w = WRITERS[TAGS[writer]]
    assert f"written by {w.app} (a {w.kind})" in msg, msg
    assert str(folder) in msg and "nothing was touched" in msg
    assert files(folder) == before
    assert not (root / "none").exists()  # before any work


@pytest.mark.parametrize("app", [a for a in APPS if a != "generate"])
def test_an_app_may_replace_its_own_earlier_output(written, app):
    ownership.check(written[app], "out_dir", app=TAGS[app])  # no refusal


def _old_stamp(folder: Path) -> Path:
    """``folder``'s stamp as an earlier version wrote it: files without writers."""
    stamp = json.loads((folder / ownership.STAMP).read_text())
    stamp.pop("writers")
    stamp["version"] = 1
    (folder / ownership.STAMP).write_text(json.dumps(stamp))
    return folder


@pytest.fixture
def old_output(root, tmp_path) -> Path:
    """An earlier version's report folder (its stamp names no writer)."""
    return _old_stamp(_made_by("swgsim-monitor", tmp_path / "reports" / "bench",
                               OUTPUT["monitor"]))


@pytest.mark.parametrize("runner", [a for a in APPS if a != "generate"])
def test_files_of_an_unknown_app_are_refused_saying_so(runners, old_output, runner):
    before = files(old_output)
    msg = refusal(lambda: runners[runner](old_output))
    assert "does not say which app wrote it" in msg and str(old_output) in msg
    assert files(old_output) == before


def test_generation_replaces_an_unknown_apps_files_only_with_overwrite(copy_of):
    folder = copy_of("ds")  # gen.generate(small_cfg(), folder)'s output
    _old_stamp(folder)
    other = small_cfg()
    other["seed"] = 5
    before = files(folder)
    msg = refusal(lambda: gen.generate(other, folder, n_jobs=1, progress=False))
    assert "does not say which app" in msg and "pass overwrite=true to replace it" in msg
    assert files(folder) == before
    # the same config resumes an earlier version's data set: nothing is replaced
    assert gen.generate(small_cfg(), folder, n_jobs=1, progress=False)["complete"]
    s = gen.generate(other, folder, n_jobs=1, progress=False, overwrite=True)
    assert s["complete"] and s["replaced"].startswith("replaced the data set")
    stamp = json.loads((folder / ownership.STAMP).read_text())
    assert {w["app"] for w in stamp["writers"].values()} == {"swgsim-generate"}


def test_generation_still_replaces_its_own_unfinished_data_set(tmp_path, monkeypatch):
    folder = tmp_path / "ds"

    def stop(*a, **k):
        raise KeyboardInterrupt

    calls = []
    real = gen.run_shard

    def second_stops(*a, **k):
        calls.append(1)
        return stop() if len(calls) == 2 else real(*a, **k)

    monkeypatch.setattr(gen, "run_shard", second_stops)
    with pytest.raises(KeyboardInterrupt):
        gen.generate(small_cfg(), folder, n_jobs=1, progress=False)
    monkeypatch.setattr(gen, "run_shard", real)
    other = small_cfg()
    other["seed"] = 5
    s = gen.generate(other, folder, n_jobs=1, progress=False)
    assert s["complete"] and s["replaced"].startswith("replaced the unfinished data set")


# ------------------------------------------------------------------ real runs (slow)
@pytest.mark.slow  # runs every app for real on its tiny preset: about 2 min on 2 cores
def test_every_app_stamps_its_files_with_its_writer(tmp_path, csv):
    """What the fixtures above fake: each app's stamp names it for every file it wrote."""
    from learn.observability.task import run_observability
    from swgcli.export import run_export_app
    from swgcli.paper import run_paper
    from swgcli.tasks import run_train

    runs = {
        "calibrate": calibrate_call(csv, tmp_path / "calibrate", "figures=false"),
        "observability": lambda: run_observability(compose_app("observability", [
            "dataset=tiny_bench", "j_out_kgm2=[0.0088]", f"data_root={tmp_path}/data",
            f"report_dir={tmp_path}/observability", "n_jobs=1", "progress=false"])),
        "export": lambda: run_export_app(compose_app("export", [
            "dataset=tiny_bench", f"out_dir={tmp_path}/export", "cross=false",
            "export.commissioning_h=2.0", "export.train_healthy_h=1.0",
            "export.train_fault_h=0.25", "export.train_variants=1",
            "export.faults=[eccentric_wg]", "export.n_trees=3", "export.forest_bytes=2000",
            "export.full_model=false"])),
        "paper": lambda: run_paper(compose_app("paper", [
            "grid=tiny", f"data_root={tmp_path}/data", f"report_root={tmp_path}/paper",
            f"tracking_uri=sqlite:///{tmp_path}/m.db", "study.figures=false",
            "study.tables=[VII]", "study.models=[nb]", "run_on=[bench]", "n_jobs=1"])),
        "monitor_evaluation": lambda: run_train(compose_app("train", [
            "experiment=monitor", "~logger", f"monitor.report_dir={tmp_path}/meval",
            *TINY_MONITOR])),
    }
    folders = {"paper": tmp_path / "paper" / "bench", "monitor_evaluation": tmp_path / "meval"}
    for app, run in runs.items():
        run()
        folder = folders.get(app, tmp_path / app)
        stamp = json.loads((folder / ownership.STAMP).read_text())
        written = {w["app"] for w in stamp["writers"].values()}
        assert written == {TAGS[app]}, (app, written)
        assert set(stamp["writers"]) == set(ownership.survey(folder).owned)
    stamp = json.loads((tmp_path / "paper" / ownership.STAMP).read_text())
    assert {w["app"] for w in stamp["writers"].values()} == {"swgsim-paper"}
    # swgsim-monitor with the evaluation's diagnosis model, into the calibration's folder
    from swgcli import dataset_preset
    from swgmon.advisories.task import run_monitor_app
    from swgsim.datasets.config import dataset_config

    life = dataset_config(dataset_preset("tiny_life"))
    life.gears = [g for g in life.gears if g.id == 3]
    gen.generate(life, tmp_path / "life", progress=False)
    (model,) = (tmp_path / "meval" / "models").glob("*.skops")
    cfg = compose_app("monitor", [f"stream={tmp_path / 'life'}", f"diagnosis_model={model}",
                                  f"out_dir={tmp_path / 'calibrate'}", "~logger"])
    before = files(tmp_path / "calibrate")
    assert "written by swgsim-calibrate" in refusal(lambda: run_monitor_app(cfg))
    assert files(tmp_path / "calibrate") == before
    shutil.rmtree(tmp_path / "calibrate")
    run_monitor_app(cfg)
    stamp = json.loads((tmp_path / "calibrate" / ownership.STAMP).read_text())
    assert {w["app"] for w in stamp["writers"].values()} == {"swgsim-monitor"}


#: A tiny monitor evaluation (one held-out gear of tiny_bench, one fault; about 30 s).
TINY_MONITOR = [
    "monitor.run_on=[tiny_bench]", "+dataset@monitor.datasets.tiny_bench=tiny_bench",
    "monitor.n_jobs=1", "monitor.progress=false", "monitor.study.seeds=[0]",
    "monitor.study.healthy_hours=3.0", "monitor.study.commissioning_h=2.0",
    "monitor.study.fault_life_h=1.0", "monitor.study.onset_window_h=[0.5,1.0]",
    "monitor.study.growth_h=0.5", "monitor.study.train_fault_h=0.25",
    "monitor.study.train_healthy_h=1.0", "monitor.study.train_variants=1",
    "monitor.study.faults=[eccentric_wg]", "monitor.study.gears=[3]",
    "monitor.study.detector_hours=1.0", "monitor.study.detectors=[]"]
