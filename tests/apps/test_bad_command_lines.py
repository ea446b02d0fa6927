"""The apps' command lines: overrides Hydra cannot parse, unknown, missing or mistyped keys,
a key under a section that is null, ``n_jobs`` out of range. Each is refused at composition
in one line naming the override or key (exit 2 from the console, the traceback only when
asked for), before any work."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from bad_input import message, one_error_line, run_app

from swgcli import compose_app
from swgcli.app import override_message

BIN = Path(sys.executable).parent


# ------------------------------------------------------------------ override syntax
@pytest.mark.parametrize("args, words", [
    (["out_dir=/tmp/my", "data"], ["override 'data': not key=value",
                                   "'out_dir=/tmp/my data'"]),
    (["out_dir=~/x"], ["override 'out_dir=~/x'", "delete prefix",
                       f"out_dir={os.path.expanduser('~/x')}", "'out_dir=\"~/x\"'"]),
    (["~no_such_key"], ["no_such_key"]),
])
def test_unparsable_overrides_name_the_override_and_how_to_quote(tmp_path, monkeypatch,
                                                                 capsys, args, words):
    code, err = run_app("swgsim-generate", ["dataset=tiny", *args], tmp_path, monkeypatch,
                        capsys)
    line = one_error_line("swgsim-generate", err)
    assert code == 2 and all(w in line for w in words), line
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["outputs"])  # no work done


def test_a_key_under_a_null_section_names_the_override(tmp_path, monkeypatch, capsys):
    """``monitor.*`` without ``experiment=monitor``: the section is null (OmegaConf asserts
    without a key); one line naming the override and the experiment that defines it."""
    code, err = run_app("swgsim-train", ["monitor.report_dir=x"], tmp_path, monkeypatch,
                        capsys)
    line = one_error_line("swgsim-train", err)
    assert code == 2 and "monitor.report_dir" in line and "experiment=monitor" in line, line


def test_a_value_with_a_space_in_one_argument_is_taken_whole():
    cfg = compose_app("generate", ["dataset=tiny", "out_dir=/tmp/my data"])
    assert cfg.out_dir == "/tmp/my data"
    assert "'out_dir=a b'" in override_message("b", ["out_dir=a", "b"])


# ------------------------------------------------------------------ keys
@pytest.mark.parametrize("app, overrides, key", [
    ("generate", ["+dataset.chain.windows_s=0.1"], "dataset.chain.windows_s: unknown key"),
    ("generate", ["dataset.chain.windows_s=0.1"], "dataset.chain.windows_s: unknown key"),
    ("generate", ["dataset.seed=abc"], "dataset.seed"),
    ("generate", ["dataset=papr"], "dataset/papr"),
    ("paper", ["grid=tny"], "Could not find 'grid/tny'; available: tiny"),  # not skipped
    ("paper", ["+study.scales=true"], "study.scales: unknown key"),
    ("paper", ["n_jobs=two"], "n_jobs"),
    ("train", ["+model.estimator.max_dept=9"], "model.estimator.max_dept"),
    ("train", ["+features.max_ordr=4"], "features.max_ordr: unknown key"),
    ("calibrate", ["out_dir=/tmp/x"], "measured: missing value"),
    ("calibrate", ["measured=a.csv", "out_dir=/tmp/x", "selection.max_iter=many"],
     "selection.max_iter"),
])
def test_unknown_missing_mistyped_keys_are_refused(app, overrides, key):
    msg = message(lambda: compose_app(app, overrides))
    assert key in msg


# ------------------------------------------------------------------ n_jobs
@pytest.mark.parametrize("app, extra, key", [
    ("generate", [], "n_jobs"),
    ("paper", [], "n_jobs"),
    ("observability", [], "n_jobs"),
    ("train", [], "n_jobs"),
    ("train", ["experiment=monitor"], "monitor.n_jobs"),
])
@pytest.mark.parametrize("value", [0, -1])
def test_n_jobs_out_of_range_is_refused_at_composition(app, extra, key, value):
    msg = message(lambda: compose_app(app, [*extra, f"{key}={value}"]))
    assert msg == f"{key} must lie in [1, inf) (worker processes), got {value}"


def test_n_jobs_is_refused_before_the_data_set_is_read(tmp_path, monkeypatch, capsys):
    code, err = run_app("swgsim-train", ["stored.path=/nowhere/data", "~logger", "n_jobs=0"],
                        tmp_path, monkeypatch, capsys)
    assert code == 2 and one_error_line("swgsim-train", err).endswith(
        "n_jobs must lie in [1, inf) (worker processes), got 0")
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["outputs"])


# ------------------------------------------------------------------ from the console
def _app(name, *args, env=None, cwd=None):
    return subprocess.run([str(BIN / name), *args], capture_output=True, text=True,
                          cwd=cwd, env={**os.environ, **(env or {})}, timeout=300)


@pytest.mark.parametrize("app, args, words", [
    ("swgsim-generate", ["dataset=tiny", "+dataset.chain.windows_s=1"], "windows_s"),
    ("swgsim-generate", ["dataset=tiny", "dataset.life={hours: 1.0}"], "dataset.life: is null"),
    ("swgsim-train", ["stored.path=/nowhere/data", "~logger"], "/nowhere/data"),
    ("swgsim-calibrate", ["measured=/nowhere/x.csv", "out_dir=out"], "/nowhere/x.csv"),
])
def test_apps_end_bad_input_in_one_line_with_exit_code_2(tmp_path, app, args, words):
    r = _app(app, *args, cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    lines = [s for s in r.stderr.splitlines() if s.strip()]
    assert lines == [lines[-1]] and lines[-1].startswith(f"{app}: error: ")
    assert words in lines[-1] and "Traceback" not in r.stderr
    full = _app(app, *args, cwd=tmp_path, env={"HYDRA_FULL_ERROR": "1"})
    assert "Traceback" in full.stderr  # asked for
