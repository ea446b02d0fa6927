"""Output folders: a link in one (followed out of it never), a file given as one, a folder
holding a user's files or a data set, and what an interrupted run leaves there. Each is
refused in one line naming the folder and its key, nothing touched (the folders compared
byte for byte), or recovered from; every app declares its output folders."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bad_input import (
    APPS,
    app_line,
    calibrate_call,
    fail_second_shard,
    friction_csv,
    message,
    one_error_line,
    run_app,
    small_cfg,
    snapshot,
)

from swgcli import compose_app, dataset_preset
from swgcli.app import check_out_dirs
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio


def files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (links not followed) and its bytes."""
    return {p.relative_to(folder).as_posix(): (p.read_bytes() if not p.is_symlink()
                                               else b"-> " + os.readlink(p).encode())
            for p in sorted(folder.rglob("*")) if p.is_file() or p.is_symlink()}


# ------------------------------------------------------------------ links
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
    from swgcli.export import run_export_app
    from swgcli.tasks import run_train
    from swgmon.advisories.task import run_monitor_app

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
def test_no_link_is_followed_out_of_an_output_folder(tmp_path, life, case):
    app, prepare, name = OUT_CASES[case]
    out = tmp_path / "out"
    prepare(out, name, tmp_path)
    before, mine = files(out), files(tmp_path / "mine") if (tmp_path / "mine").exists() else {}
    msg = message(_run_into(app, out, tmp_path, life))
    assert str(out) in msg and name in msg and "nothing was touched" in msg, msg
    assert files(out) == before
    if mine:
        assert files(tmp_path / "mine") == mine  # the link's target untouched


# ------------------------------------------------------------------ a file, a data set
def test_monitor_into_its_own_stream_folder_names_the_data_set(tmp_path, life):
    from swgmon.advisories.task import run_monitor_app
    before = files(life)
    msg = message(lambda: run_monitor_app(compose_app("monitor", [
        f"stream={life}", f"diagnosis_model={tmp_path}/m.joblib", f"out_dir={life}",
        "~logger"])))
    assert "written by swgsim-generate (a data set)" in msg and files(life) == before


def test_an_output_folder_given_as_a_file_to_the_export_and_the_monitor(tmp_path, life):
    f = tmp_path / "size.json"
    f.write_text("{}\n")
    line = app_line("export", [f"out_dir={f}"], tmp_path)
    assert line == f"swgsim-export: error: out_dir={f}: is a file, not a folder"
    line = app_line("monitor", [f"stream={life}", f"diagnosis_model={f}", f"out_dir={f}",
                                "~logger"], tmp_path)
    assert line == f"swgsim-monitor: error: out_dir={f}: is a file, not a folder"
    assert f.read_text() == "{}\n"


@pytest.mark.parametrize("prog, args, key", [
    ("swgsim-generate", ["dataset=tiny"], "out_dir"),
    ("swgsim-calibrate", ["measured=rec.csv"], "out_dir"),
    ("swgsim-monitor", ["stream=s", "diagnosis_model=m.joblib"], "out_dir"),
    ("swgsim-observability", [], "report_dir"),
    ("swgsim-observability", [], "data_root"),
    ("swgsim-paper", ["grid=tiny"], "data_root"),
    ("swgsim-paper", ["grid=tiny"], "report_root"),
    ("swgsim-train", ["stored.path=nowhere", "~logger"], "paths.report_dir"),
])
def test_a_file_given_as_an_output_folder_is_refused_before_work(
        tmp_path, monkeypatch, capsys, prog, args, key):
    (tmp_path / "thesis.tex").write_text("years of work")
    code, err = run_app(prog, [*args, f"{key}=thesis.tex"], tmp_path, monkeypatch, capsys)
    line = one_error_line(prog, err)
    assert code == 2 and line.endswith(f"{key}=thesis.tex: is a file, not a folder"), line
    assert (tmp_path / "thesis.tex").read_text() == "years of work"
    code, err = run_app(prog, [*args, f"{key}=thesis.tex/sub"], tmp_path, monkeypatch, capsys)
    line = one_error_line(prog, err)
    assert code == 2 and f"{tmp_path / 'thesis.tex'} is a file, not a folder" in line


def test_every_app_declares_its_output_folders(tmp_path):
    for name in APPS.values():
        schema = importlib.import_module(f"swgcli.{name}").main.schema
        assert schema.OUT_DIRS, name
    (tmp_path / "f").write_text("x")
    cfg = compose_app("train", ["experiment=monitor", f"monitor.report_dir={tmp_path}/f"])
    schema = importlib.import_module("swgcli.train").main.schema
    with pytest.raises(ValueError, match=r"^monitor\.report_dir=.*: is a file, not a folder$"):
        check_out_dirs(cfg, schema)


# ------------------------------------------------------------------ a user's files
def test_overwrite_refuses_a_folder_with_other_files(copy_of):
    folder = copy_of()
    (folder / "thesis.tex").write_text("years of work")
    before = snapshot(folder)
    cfg = small_cfg()
    cfg["seed"] = 7
    msg = message(lambda: gen.generate(cfg, folder, progress=False, overwrite=True))
    assert str(folder) in msg and "thesis.tex" in msg
    assert snapshot(folder) == before


def test_main_job_refuses_a_data_root_with_other_files(tmp_path):
    folder = tmp_path / "data" / "paper"
    folder.mkdir(parents=True)
    (folder / "notes.txt").write_text("mine")
    cfg = compose_app("paper", ["grid=tiny", f"data_root={tmp_path}/data",
                                f"report_root={tmp_path}/reports",
                                f"tracking_uri=sqlite:///{tmp_path}/m.db"])
    from swgcli.paper import run_paper

    msg = message(lambda: run_paper(cfg))
    assert str(folder) in msg and "notes.txt" in msg
    assert (folder / "notes.txt").read_text() == "mine"
    assert not (tmp_path / "reports").exists()


# ------------------------------------------------------------------ an interrupted run
def test_an_unfinished_run_never_blocks_a_corrected_rerun(tmp_path, monkeypatch):
    real = gen.run_shard
    fail_second_shard(monkeypatch, gen)
    out = tmp_path / "ds"
    with pytest.raises(RuntimeError):
        gen.generate(small_cfg(), out, n_jobs=1, progress=False)
    monkeypatch.setattr(gen, "run_shard", real)
    fixed = small_cfg()
    fixed["seed"] = 11  # the corrected run has another config, and no overwrite flag
    s = gen.generate(fixed, out, n_jobs=1, progress=False)
    assert s["complete"] and "unfinished data set" in s["replaced"]


def test_temporary_files_of_a_killed_run_are_cleaned(copy_of):
    folder = copy_of()
    (folder / dsio.MANIFEST).unlink()  # killed before the end: no manifest
    code = ("import os, sys; from pathlib import Path; from swgsim.files import atomic, ownership; "
            "f = Path(sys.argv[1]); ownership.join(f.parent); "
            "(f.parent / (atomic.temp_prefix(f) + 'k.tmp')).write_bytes(b'half'); os._exit(0)")
    subprocess.run([sys.executable, "-c", code, str(folder / "gear1_n4000rpm.nc")], check=True)
    assert len(list(folder.glob("*.tmp"))) == 1  # its stamp names the killed run: ours
    gen.generate(small_cfg(), folder, n_jobs=1, progress=False)
    assert not list(folder.glob("*.tmp")) and (folder / dsio.MANIFEST).is_file()
