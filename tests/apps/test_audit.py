"""Reliability audit of the apps added since the last one (issue 35): the monitor, the
export, gear lives, operating profiles, measured files, run as a stranger would.

Every case is a row, grouped by root cause: it ends in one clear line naming the key or
file (exit 2 where the app itself is run), or in a correct recovery; nothing a user made is
lost (the folders involved are compared byte for byte); no symlink is followed out of an
output folder; a manifest naming a shard outside its folder is refused. Shared fixtures
keep it to about a minute on two cores: one tiny life (60 windows) and one small grid data
set, generated once; apps run in-process through their real ``main`` (Hydra, the one-line
wrapper) where the console is what is audited, else through their task functions.

The two cases first found failing outside this issue's files (a life of 1e30 h, a severity
beyond Table V named by half its key) hold now and run as ordinary rows.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from bad_input import calibrate_call, friction_csv, message, small_cfg

from swgcli import dataset_preset
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio
from swgsim.files import ownership


def files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (links not followed) and its bytes."""
    return {p.relative_to(folder).as_posix(): (p.read_bytes() if not p.is_symlink()
                                               else b"-> " + os.readlink(p).encode())
            for p in sorted(folder.rglob("*")) if p.is_file() or p.is_symlink()}


def app_line(module: str, args: list[str], tmp_path: Path) -> str:
    """Run ``swgcli.<module>.main`` in-process as the console would; its one line (exit 2)."""
    import importlib

    main = importlib.import_module(f"swgcli.{module}").main
    argv, sys.argv = sys.argv, [module, *args, f"hydra.run.dir={tmp_path}/hydra"]
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as info:
            main()
    finally:
        sys.argv = argv
    lines = [s for s in err.getvalue().splitlines() if s.strip()]
    assert info.value.code == 2 and len(lines) == 1, err.getvalue()
    assert "Traceback" not in err.getvalue()
    return lines[0]


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("audit")


@pytest.fixture(scope="module")
def life(root) -> Path:
    """A finished tiny life of gear 3 (2 h, a window every 2 min, an eccentric WG from
    1.5 h on), as swgsim-generate writes it."""
    cfg = dataset_preset("tiny_life")
    cfg["gears"] = [g for g in cfg["gears"] if g["id"] == 3]
    cfg["life"].update(hours=2.0, commissioning_h=1.0, interval_min=2.0)
    cfg["life"]["fault"]["onset_h"] = 1.5
    gen.generate(cfg, root / "life", n_jobs=1, progress=False)
    return root / "life"


@pytest.fixture(scope="module")
def grid(root) -> Path:
    gen.generate(small_cfg(), root / "grid", n_jobs=1, progress=False)
    return root / "grid"


# ------------------------------------------------------------------ A output folders
def _outside(tmp_path: Path) -> Path:
    """A user's file outside every output folder."""
    f = tmp_path / "mine" / "notes.md"
    f.parent.mkdir()
    f.write_text("# my notes\n")
    return f


def _link_file(out: Path, name: str, tmp_path: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / name).symlink_to(_outside(tmp_path))


def _link_dir(out: Path, name: str, tmp_path: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / name).symlink_to(_outside(tmp_path).parent, target_is_directory=True)


def _dangling(out: Path, name: str, tmp_path: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / name).symlink_to(tmp_path / "gone")


OUT_CASES = {  # case -> (app, how the output folder is prepared, name)
    "monitor: summary.json a link out": ("monitor", _link_file, "summary.json"),
    "monitor: report.md a dangling link": ("monitor", _dangling, "report.md"),
    "export: size.json a link out": ("export", _link_file, "size.json"),
    "export: swg_monitor.c a link out": ("export", _link_file, "swg_monitor.c"),
    "calibrate: figures/ a link to a folder": ("calibrate", _link_dir, "figures"),
    "calibrate: report.md a link out": ("calibrate", _link_file, "report.md"),
    "generate (life): its shard name a link out": ("generate", _link_file, "gear3_life.nc"),
    "generate (life): manifest.json a link out": ("generate", _link_file, "manifest.json"),
    "monitor evaluation: parts/ a link to a folder": ("monitor_evaluation", _link_dir,
                                                      "parts"),
    "monitor evaluation: models/ a dangling link": ("monitor_evaluation", _dangling,
                                                    "models"),
}


def _run_into(app: str, out: Path, tmp_path: Path, life: Path):
    from learn.tasks.train import run_train
    from swgcli import compose_app
    from swgcli.export import run_export_app
    from swgcli.monitor import run_monitor_app

    if app == "monitor":
        return lambda: run_monitor_app(compose_app("monitor", [
            f"stream={life}", f"diagnosis_model={tmp_path}/none.joblib", f"out_dir={out}",
            "~logger"]))
    if app == "export":
        return lambda: run_export_app(compose_app("export", ["dataset=tiny_bench",
                                                             f"out_dir={out}"]))
    if app == "calibrate":
        t = np.arange(2000) * 0.002
        csv = friction_csv(tmp_path / "rec.csv", t, np.sin(t), np.cos(t))
        return calibrate_call(csv, out)
    if app == "generate":
        cfg = dataset_preset("tiny_life")
        return lambda: gen.generate(cfg, out, n_jobs=1, progress=False, overwrite=True)
    return lambda: run_train(compose_app("train", [
        "experiment=monitor", "~logger", "monitor.run_on=[bench]",
        f"monitor.report_dir={out}"]))


@pytest.mark.parametrize("case", OUT_CASES)
def test_A_no_link_is_followed_out_of_an_output_folder(tmp_path, life, case):
    app, prepare, name = OUT_CASES[case]
    out = tmp_path / "out"
    prepare(out, name, tmp_path)
    before, mine = files(out), files(tmp_path / "mine") if (tmp_path / "mine").exists() else {}
    msg = message(_run_into(app, out, tmp_path, life))
    assert str(out) in msg and name in msg and "nothing was touched" in msg, msg
    assert files(out) == before
    if mine:
        assert files(tmp_path / "mine") == mine  # the link's target untouched


def test_A_monitor_into_its_own_stream_folder_names_the_data_set(tmp_path, life):
    from swgcli import compose_app
    from swgcli.monitor import run_monitor_app
    before = files(life)
    msg = message(lambda: run_monitor_app(compose_app("monitor", [
        f"stream={life}", f"diagnosis_model={tmp_path}/m.joblib", f"out_dir={life}",
        "~logger"])))
    assert "written by swgsim-generate (a data set)" in msg and files(life) == before


def test_A_output_folder_given_as_a_file(tmp_path, life):
    f = tmp_path / "size.json"
    f.write_text("{}\n")
    line = app_line("export", [f"out_dir={f}"], tmp_path)
    assert line == f"swgsim-export: error: out_dir={f}: is a file, not a folder"
    line = app_line("monitor", [f"stream={life}", f"diagnosis_model={f}", f"out_dir={f}",
                                "~logger"], tmp_path)
    assert line == f"swgsim-monitor: error: out_dir={f}: is a file, not a folder"
    assert f.read_text() == "{}\n"


# ------------------------------------------------------------------ B a data set on disk
def _manifest(folder: Path, change) -> None:
    mf = folder / dsio.MANIFEST
    m = json.loads(mf.read_text())
    change(m)
    mf.write_text(json.dumps(m))


def _rename_shard(new: str):
    def change(m):
        (old, entry), = m["shards"].items()
        m["shards"] = {new: entry}
    return lambda f: _manifest(f, change)


def _fifo(name: str):
    def make(f: Path):
        (f / name).unlink()
        os.mkfifo(f / name)
    return make


def _to_dev_zero(name: str):
    def make(f: Path):
        (f / name).unlink()
        (f / name).symlink_to("/dev/zero")
    return make


def _flip_byte(f: Path):
    p = f / "gear3_life.nc"
    b = bytearray(p.read_bytes())
    b[len(b) // 2] ^= 0xFF
    p.write_bytes(bytes(b))


DATA_CASES = {  # case -> (how the copy of the life is spoiled, what the line names)
    "shard named ../x.nc": (_rename_shard("../x.nc"), "'../x.nc' is not a file name"),
    "shard named by an absolute path": (_rename_shard("/etc/passwd.nc"),
                                        "'/etc/passwd.nc' is not a file name"),
    "shard in a subfolder": (_rename_shard("sub/gear3_life.nc"), "is not a file name"),
    "shard not *.nc": (_rename_shard("gear3_life.json"), "not *.nc"),
    "manifest.json a FIFO": (_fifo(dsio.MANIFEST), "is not a regular file"),
    "manifest.json a link to /dev/zero": (_to_dev_zero(dsio.MANIFEST),
                                          "is not a regular file"),
    "shard a FIFO": (_fifo("gear3_life.nc"), "is not a regular file"),
    "shard a link to /dev/zero": (_to_dev_zero("gear3_life.nc"), "is not a regular file"),
    "one byte of the shard flipped": (_flip_byte, "gear3_life.nc"),
    "an extra shard": (lambda f: shutil.copy(f / "gear3_life.nc", f / "gear9_life.nc"),
                       "gear9_life.nc"),
    "manifest not JSON": (lambda f: (f / dsio.MANIFEST).write_text("{"), "not valid JSON"),
    "manifest incomplete": (lambda f: _manifest(f, lambda m: m.update(complete=False)),
                            "incomplete"),
    "manifest of another schema": (lambda f: _manifest(
        f, lambda m: m.update(schema_version=2)), "schema_version 2"),
    "a shard's SHA-256 missing": (lambda f: _manifest(
        f, lambda m: next(iter(m["shards"].values())).pop("sha256")), "sha256 is missing"),
}


@pytest.mark.parametrize("case", DATA_CASES)
def test_B_a_spoiled_data_set_is_refused_in_one_line(tmp_path, life, case):
    spoil, named = DATA_CASES[case]
    folder = tmp_path / "life"
    shutil.copytree(life, folder, symlinks=True)
    spoil(folder)
    msg = message(lambda: dsio.load(folder))
    assert named in msg, msg


def test_B_the_monitor_app_refuses_a_manifest_pointing_out(tmp_path, life):
    folder = tmp_path / "life"
    shutil.copytree(life, folder)
    _rename_shard("../outside.nc")(folder)
    model = tmp_path / "m.joblib"
    import joblib

    from learn.monitor.model import DiagnosisModel
    joblib.dump(DiagnosisModel.__new__(DiagnosisModel), model)
    line = app_line("monitor", [f"stream={folder}", f"diagnosis_model={model}",
                                "trust_pickle=true", f"out_dir={tmp_path}/out", "~logger"],
                    tmp_path)
    assert "'../outside.nc' is not a file name in its folder" in line
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ C a stream
@pytest.fixture(scope="module")
def stream(life):
    return dsio.load(life)


def _model(ds):
    fs = float(ds.attrs["sample_rate_hz"])
    pts = np.stack([ds["n_in_rpm"].values, ds["t_out_nm"].values], axis=1)
    return types.SimpleNamespace(sample_rate_hz=fs, window_s=ds.sizes["time"] / fs,
                                 points_range=np.array([pts.min(0), pts.max(0)]),
                                 n_features=0)


def _hours(f):
    return lambda ds: ds.assign(hour=("sample", f(ds["hour"].values.copy())))


def _set(values):
    def f(h):
        h[:len(values)] = values
        return h
    return f


STREAM_CASES = {
    "negative hours": (_hours(lambda h: h - 5.0), "'hour' must be finite and >= 0"),
    "a NaN hour": (_hours(_set([0.0, np.nan])), "'hour' must be finite and >= 0"),
    "an infinite hour": (_hours(lambda h: np.r_[h[:-1], np.inf]), "finite and >= 0"),
    "hours going back": (_hours(_set([0.0, 1.0, 0.5])), "hours must increase"),
    "one window": (lambda ds: ds.isel(sample=[0]), "hours must increase"),
    "no commissioning": (lambda ds: ds.assign(commissioning=("sample", np.zeros(
        ds.sizes["sample"], bool))), "commissioning windows must be the first"),
    "commissioning late": (lambda ds: ds.assign(commissioning=("sample", np.r_[
        False, ds["commissioning"].values[1:]])), "commissioning windows must be the first"),
    "all commissioning": (lambda ds: ds.assign(commissioning=("sample", np.ones(
        ds.sizes["sample"], bool))), "has no windows after commissioning to monitor"),
    "a bridge missing": (lambda ds: ds.isel(sensor=[0, 1, 2, 3]), "bridges"),
    "no hour variable (a grid data set)": (lambda ds: ds.drop_vars("hour"), "'hour'"),
    "sample rate off": (lambda ds: ds.assign_attrs(sample_rate_hz=2 * ds.attrs[
        "sample_rate_hz"]), "sample rate"),
    "a load outside the model's range": (lambda ds: ds.assign(t_out_nm=ds["t_out_nm"] * 10),
                                         "outside the model's training range"),
}


@pytest.mark.parametrize("case", STREAM_CASES)
def test_C_a_stream_the_monitor_cannot_take_is_refused(stream, case):
    from learn.monitor.rule import RuleConfig
    from learn.monitor.stream import check_stream

    spoil, named = STREAM_CASES[case]
    ds = spoil(stream.copy())
    msg = message(lambda: check_stream(ds, _model(stream), RuleConfig(min_normal_windows=2),
                                       "stream=life"))
    assert msg.startswith("stream=life") and named in msg, msg


# ------------------------------------------------------------------ D a model file
def _pickled(obj):
    def make(p: Path):
        import joblib
        joblib.dump(obj, p)
    return make


MODEL_CASES = {
    "/dev/zero": ("/dev/zero", "is a character device, not a regular file"),
    "a FIFO": (lambda p: os.mkfifo(p), "is a FIFO"),
    "a folder": (lambda p: p.mkdir(), "is a folder"),
    "a sparse 3 GB file": (lambda p: subprocess.run(["truncate", "-s", "3G", str(p)],
                                                    check=True), "over the 2.00 GiB"),
    "a sparse 1 GB file": (lambda p: subprocess.run(["truncate", "-s", "1G", str(p)],
                                                    check=True), "a sparse file"),
    "random bytes": (lambda p: p.write_bytes(os.urandom(4096)), "is a pickle, which runs any "
                                                                  "code it names"),
    "a pickled dict": (_pickled({"model": 1}), "is a pickle, which runs any code it names"),
    "a trusted pickled dict": (_pickled({"model": 1}), "holds a dict, not a diagnosis model"),
    "a .skops without its card": (lambda p: p.with_suffix(".skops").write_bytes(b"x" * 64),
                                  "has no readable model card"),
    "a .skops changed after its card": ("changed", "SHA-256 differs"),
    "a card of another file": ("other card", "is not that of"),
    "missing": (lambda p: None, "no diagnosis model"),
}


def _skops_case(tmp_path: Path, case: str) -> Path:
    """A real model file and card, then spoiled."""
    from sklearn.ensemble import HistGradientBoostingClassifier

    from learn.monitor.model import DiagnosisModel
    from learn.monitor.model_io import save_model

    clf = HistGradientBoostingClassifier(max_iter=2).fit(np.eye(4), [0, 1, 0, 1])
    p = save_model(DiagnosisModel(["healthy", "x"], clf), tmp_path / "m", [])
    if case == "changed":
        data = bytearray(p.read_bytes())
        data[-20] ^= 1
        p.write_bytes(bytes(data))
    else:
        card = p.with_name("m.card.json")
        card.write_text(card.read_text().replace('"m.skops"', '"other.skops"'))
    return p


@pytest.mark.parametrize("case", MODEL_CASES)
def test_D_a_diagnosis_model_that_is_none_is_refused_before_reading(tmp_path, life, case):
    make, named = MODEL_CASES[case]
    if make in ("changed", "other card"):
        p = _skops_case(tmp_path, make)
    else:
        p = Path(make) if isinstance(make, str) else tmp_path / "model.joblib"
        if "skops" in case:
            p = p.with_suffix(".skops")
        if not isinstance(make, str):
            make(p)
    trust = ["trust_pickle=true"] if "trusted" in case else []
    line = app_line("monitor", [f"stream={life}", f"diagnosis_model={p}", *trust,
                                f"out_dir={tmp_path}/out", "~logger"], tmp_path)
    assert line.startswith("swgsim-monitor: error: ") and named in line, line
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ E, F app options
OPTION_CASES = {  # case -> (app, overrides, the key the line must name)
    "monitor rule.design_hours=0": ("monitor", ["rule.design_hours=0"], "rule.design_hours"),
    "monitor rule.shift_sigma=-1": ("monitor", ["rule.shift_sigma=-1"], "rule.shift_sigma"),
    "monitor rule.max_delay_windows=0": ("monitor", ["rule.max_delay_windows=0"],
                                         "rule.max_delay_windows"),
    "monitor rule.min_normal_windows=1": ("monitor", ["rule.min_normal_windows=1"],
                                          "rule.min_normal_windows"),
    "monitor confirm_h=-1": ("monitor", ["confirm_h=-1"], "confirm_h"),
    "monitor confirm_h=nan": ("monitor", ["confirm_h=nan"], "confirm_h"),
    "monitor an unknown rule key": ("monitor", ["rule.bogus=1"], "rule.bogus: unknown key"),
    "monitor an old key": ("monitor", ["rule.min_baseline=3"], "rule.min_normal_windows"),
    "monitor gear=9": ("monitor", ["gear=9", "diagnosis_model=MODEL"], "gear"),
    "export held_out_gear=9": ("export", ["export.held_out_gear=9"], "export.held_out_gear"),
    "export n_trees=0": ("export", ["export.n_trees=0"], "export.n_trees"),
    "export forest_bytes=1": ("export", ["export.forest_bytes=1"], "export.forest_bytes"),
    "export an unknown fault": ("export", ["export.faults=[bogus]"], "export.faults"),
    "export train_variants=0": ("export", ["export.train_variants=0"],
                                "export.train_variants"),
    "export commissioning_h=-1": ("export", ["export.commissioning_h=-1"],
                                  "export.commissioning_h"),
    "export an unknown key": ("export", ["export.bogus=1"], "export.bogus: unknown key"),
}


@pytest.fixture(scope="module")
def any_model(root) -> Path:
    """A file holding a diagnosis model object (empty: the cases are refused before it is
    used)."""
    import joblib

    from learn.monitor.model import DiagnosisModel
    p = root / "empty.joblib"
    joblib.dump(DiagnosisModel.__new__(DiagnosisModel), p)
    return p


@pytest.mark.parametrize("case", OPTION_CASES)
def test_E_F_a_bad_monitor_or_export_option_is_one_line(tmp_path, life, any_model, case):
    app, over, key = OPTION_CASES[case]
    over = [o.replace("MODEL", str(any_model)) for o in over]
    model = [] if any(o.startswith("diagnosis_model=") for o in over) else [
        f"diagnosis_model={tmp_path}/m.joblib"]
    base = ([f"stream={life}", *model, "trust_pickle=true", "~logger"] if app == "monitor"
            else ["dataset=tiny_bench", "cross=false"])
    line = app_line(app, [*base, f"out_dir={tmp_path}/out", *over], tmp_path)
    assert line.startswith(f"swgsim-{app}: error: ") and key in line, line
    assert not (tmp_path / "out").exists()


def test_F_a_failing_cross_tool_is_reported_not_measured(tmp_path, monkeypatch):
    """The Cortex-M4F figures when the cross compiler fails: 'not measured (why)' in the
    target and in size.json; swgsim-export ends with exit 2 and one line."""
    from learn.export import pipeline, target

    fake = tmp_path / "bin"
    fake.mkdir()
    for tool in (target.CROSS, target.QEMU):
        (fake / tool).write_text(f"#!/bin/sh\necho '{tool}: fatal error: no crt0.o' >&2\n"
                                 "exit 1\n")
        (fake / tool).chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake}:{os.environ['PATH']}")
    held = types.SimpleNamespace(signals=np.zeros((1, 5, 8), np.float32), op=np.zeros(1, int),
                                 efficiency=np.ones(1), feats=np.zeros((1, 3), np.float32))
    tables = types.SimpleNamespace(points=np.array([[2000.0, 7.0]]), fs_hz=1e4, n_t=8)
    t = pipeline.target_figures(tmp_path, tables, held, None, cross=True)
    assert t == {"measured": False, "failed": t["why"],
                 "why": f"{target.CROSS} failed (exit 1): {target.CROSS}: fatal error: no "
                        "crt0.o"}
    rec = pipeline.size_record({"target": t, "host_c": {"accuracy_c": 0.9},
                                "accuracy_python": 0.9, "windows": {"held_out": 1},
                                "dataset": "d", "held_out_gear": 3})
    assert rec["flash_bytes"] is None and rec["target"] == f"not measured ({t['why']})"
    from swgcli import export as app

    summary = {"size": rec, "host_c": {"accuracy_c": 0.9, "host_c": "checked"},
               "held_out_gear": 3, "accuracy_python": 0.9, "target": t,
               "files": [str(tmp_path / "swg_monitor.c")], "failed": [t["why"]]}
    monkeypatch.setattr(app, "run_export_app", lambda cfg: summary)
    line = app_line("export", ["dataset=tiny_bench", f"out_dir={tmp_path}/x"], tmp_path)
    assert line.startswith(f"swgsim-export: error: {t['why']}; the C files, size.json")


# ------------------------------------------------------------------ G lives
LIFE_CASES = {  # case -> (change to the tiny_life preset, the key the line must name)
    "hours=-1": ({"hours": -1.0}, "dataset.life.hours"),
    "hours=nan": ({"hours": float("nan")}, "dataset.life.hours"),
    "interval_min=0": ({"interval_min": 0.0}, "dataset.life.interval_min"),
    "commissioning beyond the life": ({"commissioning_h": 9.0},
                                      "dataset.life.commissioning_h"),
    "an unknown fault": ({"fault": {"fault": "bogus"}}, "dataset.life.fault.fault"),
    "a fault before commissioning ends": ({"fault": {"onset_h": 1.0}},
                                          "dataset.life.fault.onset_h"),
    "a linear growth of 0 h": ({"fault": {"growth": "linear", "growth_h": 0.0}},
                               "dataset.life.fault.growth_h"),
    "an unknown growth": ({"fault": {"growth": "bogus"}}, "dataset.life.fault.growth"),
    "points going back": ({"fault": {"growth": "points",
                                     "points": [[6.0, 0.0], [5.0, 0.1]]}},
                          "dataset.life.fault.points"),
    "a sensor fault on bridge 7": ({"fault": {"fault": "sensor_offset_step", "sensor": 7,
                                              "severity": 0.05}},
                                   "dataset.life.fault.sensor"),
    "a position of nan degrees": ({"fault": {"position_deg": float("nan")}},
                                  "dataset.life.fault.position_deg"),
    "a sensor fault on bridge -1": ({"fault": {"fault": "sensor_offset_step", "sensor": -1,
                                               "severity": 0.05}},
                                    "dataset.life.fault.sensor"),
    "hours=1e30": ({"hours": 1e30}, "dataset.life.hours"),
    "a severity beyond Table V": ({"fault": {"severity": 5.0}},
                                  "dataset.life.fault.severity"),
}


def _life_cfg(change: dict) -> dict:
    cfg = dataset_preset("tiny_life")
    fault = change.pop("fault", {})
    cfg["life"].update(change)
    cfg["life"]["fault"].update(fault)
    return cfg


@pytest.mark.parametrize("case", LIFE_CASES)
def test_G_a_bad_life_is_refused_naming_its_key(tmp_path, case):
    from swgsim.datasets.plan import plan

    change, key = LIFE_CASES[case]
    cfg = _life_cfg(json.loads(json.dumps(change)))
    msg = message(lambda: plan(cfg))
    assert msg.startswith(key) or f" {key}" in msg, msg


def test_G_integer_hours_in_points_are_explained(tmp_path):
    line = app_line("generate", ["dataset=tiny_life", "dataset.life.fault.growth=points",
                                 "dataset.life.fault.points=[[6,0.0],[7,0.1]]",
                                 f"out_dir={tmp_path}/ds"], tmp_path)
    assert line == ("swgsim-generate: error: dataset.life.fault.points[0]: 6 is an integer "
                    "where a float is required (OmegaConf checks the numbers of nested lists "
                    "strictly); write it with a decimal point: 6.0")
    assert not (tmp_path / "ds").exists()


# ------------------------------------------------------------------ H profiles
PROFILE_CASES = {  # case -> (change to the tiny_motion preset's profile, the key)
    "input_counts_per_rev=0": ({"angles": {"input_counts_per_rev": 0}},
                               "dataset.profile.angles.input_counts_per_rev must be an "
                               "integer in [1, 4294967296]"),
    "output_encoder_bits=40": ({"angles": {"output_encoder_bits": 40}},
                               "dataset.profile.angles.output_encoder_bits must be an "
                               "integer in [8, 32]"),
    "output_encoder_bits=7": ({"angles": {"output_encoder_bits": 7}},
                              "dataset.profile.angles.output_encoder_bits"),
    "a load step after the profile": (
        {"load": {"steps": {"initial_nm": 7.0, "steps": [{"time_s": 5.0,
                                                          "torque_nm": 30.0}]}}},
        "dataset.profile.load.steps.steps[0].time_s must lie in [0, 0.4] s"),
    "a load step before it": (
        {"load": {"steps": {"initial_nm": 7.0, "steps": [{"time_s": -1.0,
                                                          "torque_nm": 30.0}]}}},
        "dataset.profile.load.steps.steps[0].time_s"),
    "a load beyond the peak torque": (
        {"load": {"steps": {"initial_nm": 200.0, "steps": []}}},
        "dataset.profile.load.steps.initial_nm"),
    "a speed beyond the catalogue": (
        {"segments": [{"move": {"target_rpm": 9000.0, "accel_rpm_s": 4e4}}]},
        "dataset.profile.segments[0].move.target_rpm"),
    "an acceleration beyond the torque": (
        {"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 1e9}}]},
        "dataset.profile.segments[0].move.accel_rpm_s"),
    "a negative hold": (
        {"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 4e4}},
                      {"hold": {"duration_s": -0.1}}]},
        "dataset.profile.segments[1].hold.duration_s"),
    "a window start after the profile": ({"window_starts_s": [0.39]},
                                         "dataset.profile.window_starts_s[0]"),
    "a negative start jitter": ({"start_jitter_s": -0.01},
                                "dataset.profile.start_jitter_s"),
    "a hold of 1e9 s": (
        {"segments": [{"move": {"target_rpm": 2000.0, "accel_rpm_s": 4e4}},
                      {"hold": {"duration_s": 1e9}}]},
        "dataset.profile.segments last 1e+09 s; allowed: at most 600 s"),
}


@pytest.mark.parametrize("case", PROFILE_CASES)
def test_H_a_bad_profile_is_refused_naming_its_key(case):
    from swgsim.datasets.plan import plan

    change, key = PROFILE_CASES[case]
    cfg = dataset_preset("tiny_motion")
    for k, v in change.items():
        if isinstance(v, dict) and isinstance(cfg["profile"].get(k), dict) and k != "load":
            cfg["profile"][k].update(v)
        else:
            cfg["profile"][k] = v
    msg = message(lambda: plan(cfg))
    assert msg.startswith(key), msg


# ------------------------------------------------------------------ I monitor evaluation
EVAL_CASES = {  # case -> (overrides of swgsim-train experiment=monitor, the key)
    "an unknown fault": (["monitor.study.faults=[bogus]"], "monitor.study.faults: ['bogus']"),
    "a gear the data sets lack": (["monitor.study.gears=[7]"], "monitor.study.gears: [7]"),
    "an unknown detector": (["monitor.study.detectors=[bogus]"], "monitor.study.detectors"),
    "an unknown data set": (["monitor.run_on=[nope]"], "monitor.run_on"),
    "n_jobs=0": (["monitor.n_jobs=0"], "monitor.n_jobs"),
    "commissioning as long as the life": (["monitor.study.commissioning_h=1000"],
                                          "monitor.study.commissioning_h"),
    "a negative seed": (["monitor.study.seeds=[-1]"], "monitor.study.seeds[0]"),
    "design_hours=0": (["monitor.study.rule.design_hours=0"],
                       "monitor.study.rule.design_hours"),
    "an old key": (["monitor.study.baselines=[paper_rf]"], "monitor.study.detectors"),
    "a device that is none": (["monitor.device=gpu"], "monitor.device: must be one of"),
}


@pytest.mark.parametrize("case", EVAL_CASES)
def test_I_a_bad_evaluation_is_one_line_before_any_work(tmp_path, case):
    over, key = EVAL_CASES[case]
    line = app_line("train", ["experiment=monitor", "~logger",
                              f"monitor.report_dir={tmp_path}/rep", *over], tmp_path)
    assert line.startswith("swgsim-train: error: ") and key in line, line
    assert not (tmp_path / "rep").exists()


# ------------------------------------------------------------------ K measured files
T = np.arange(2000) * 0.002


def _csv(t, q, dq):
    return lambda p: friction_csv(p, t, q, dq, 0.1 * np.tanh(20 * np.cos(T)))


MEASURED_CASES = {  # case -> (how the file is made, what the line says)
    "/dev/zero": ("/dev/zero", "measured /dev/zero: is a character device"),
    "a FIFO": (lambda p: os.mkfifo(p), "is a FIFO (named pipe), not a regular file"),
    "a sparse 2 GB file": (lambda p: subprocess.run(["truncate", "-s", "2G", str(p)],
                                                    check=True), "a sparse file (2.00 GiB"),
    "a folder without manifest": (lambda p: p.mkdir(), "is a directory without manifest"),
    "a binary file": (lambda p: p.write_bytes(b"time_s,q\x00\x01" * 100), "NUL bytes"),
    "a first line over 64 KiB": (lambda p: p.write_text("x" * 70_000),
                                 "no line end in its first 64 KiB"),
    "time column twice too long": (_csv(2 * T, np.sin(T), np.cos(T)),
                                   "but 2.00 times it (a pure factor"),
    "velocity in deg/s": (_csv(T, np.sin(T), np.rad2deg(np.cos(T))), "looks like deg/s"),
    "velocity in rpm": (_csv(T, np.sin(T), np.cos(T) * 60 / (2 * np.pi)),
                        "looks like rpm"),
    "velocity of the wrong sign": (_csv(T, np.sin(T), -np.cos(T)), "a sign error"),
    "time in ms": (_csv(T * 1000, np.sin(T), np.cos(T)), "time_s looks like milliseconds"),
    "angle in degrees": (_csv(T, np.rad2deg(np.sin(T)), np.cos(T)),
                         "q_rad looks like degrees"),
}


@pytest.mark.parametrize("case", MEASURED_CASES)
def test_K_a_measured_file_is_refused_in_one_line_before_it_is_read(tmp_path, case):
    import resource

    make, named = MEASURED_CASES[case]
    p = Path(make) if isinstance(make, str) else tmp_path / "rec.csv"
    if not isinstance(make, str):
        make(p)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    msg = message(calibrate_call(p, tmp_path / "out"))
    assert named in msg, msg
    # no memory growth: the largest resident size grew by under 100 MiB
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss < 100 * 1024
    assert not (tmp_path / "out").exists()


@pytest.mark.slow  # a real export of the tiny bench grid: about 25 s
def test_F_a_failing_cross_tool_leaves_every_file_listed(tmp_path, monkeypatch):
    from learn.export import target
    from swgcli import compose_app
    from swgcli.export import run_export_app

    fake = tmp_path / "bin"
    fake.mkdir()
    for tool in (target.CROSS, target.QEMU):
        (fake / tool).write_text(f"#!/bin/sh\necho '{tool}: fatal error' >&2\nexit 1\n")
        (fake / tool).chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake}:{os.environ['PATH']}")
    out = tmp_path / "export"
    s = run_export_app(compose_app("export", [
        "dataset=tiny_bench", f"out_dir={out}", "export.commissioning_h=1.0",
        "export.train_healthy_h=0.5", "export.train_fault_h=0.1", "export.train_variants=1",
        "export.faults=[eccentric_wg]", "export.n_trees=2", "export.forest_bytes=500",
        "export.full_model=false"]))
    why = f"{target.CROSS} failed (exit 1): {target.CROSS}: fatal error"
    assert s["failed"] == [why] and s["target"]["why"] == why
    size = json.loads((out / "size.json").read_text())
    assert size["target"] == f"not measured ({why})" and size["flash_bytes"] is None
    assert json.loads((out / "summary.json").read_text())["failed"] == [why]
    found = ownership.survey(out)  # every file written is listed in the stamp
    assert found.foreign == [] and found.stale == [] and {"size.json", "summary.json",
                                                          "swg_monitor.c"} <= set(found.owned)
    assert {w.app for w in found.writers.values()} == {"swgsim-export"}
