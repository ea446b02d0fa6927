"""Everything a run needs is checked before its work: a broken install (a package that
raises at import, planted on ``PYTHONPATH``) is one line naming the package, exit 2,
nothing written; a tracking store MLflow cannot open is refused before any work."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest
from bad_input import run_app

from learn.tracking.preflight import BrokenInstall, check_imports

ROOT = Path(__file__).resolve().parents[2]


def _plant(tmp_path: Path, package: str) -> Path:
    """A folder holding a package ``package`` that raises ImportError when imported."""
    site = tmp_path / "broken"
    (site / package).mkdir(parents=True)
    (site / package / "__init__.py").write_text(
        f"raise ImportError('{package} planted broken by the test')\n")
    return site


def test_check_imports_names_the_package_in_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "swg_missing_dep", None)  # import raises ImportError
    check_imports(["json", "numpy"])
    with pytest.raises(BrokenInstall) as e:
        check_imports(["json", "swg_missing_dep", "numpy"])
    line = str(e.value)
    assert isinstance(e.value, ValueError) and "\n" not in line
    assert line.startswith("broken install: swg_missing_dep cannot be imported (")
    assert "reinstall with bash scripts/quickstart.sh" in line


def test_any_failure_at_import_is_a_broken_install(tmp_path, monkeypatch):
    site = tmp_path / "site"
    site.mkdir()
    (site / "swg_bad_dep.py").write_text("raise RuntimeError('bad build')\n")
    monkeypatch.syspath_prepend(str(site))
    with pytest.raises(BrokenInstall, match=r"swg_bad_dep cannot be imported \("
                                            r"RuntimeError: bad build\)"):
        check_imports(["swg_bad_dep"])


def _app(tmp_path: Path, module: str, args: list[str], broken: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(_plant(tmp_path, broken)), str(ROOT), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-m", f"swgcli.{module}", *args,
                           f"hydra.run.dir={tmp_path}/hydra"],
                          capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)


@pytest.mark.parametrize(("module", "broken", "args", "out"), [
    # mlflow imports cryptography (as in the broken install): named through mlflow;
    # the monitor's evaluation reads no file, so its inputs pass and the imports are next
    ("train", "cryptography", ["experiment=monitor"], "reports"),
    ("generate", "h5netcdf", ["dataset=tiny"], "data"),
])
def test_a_broken_install_is_one_line_before_any_work(tmp_path, module, broken, args, out):
    r = _app(tmp_path, module, [*args, f"paths.report_dir={tmp_path}/reports"
                                if module == "train" else f"out_dir={tmp_path}/data"], broken)
    lines = [s for s in r.stderr.splitlines() if s.strip()]
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    prog = "swgsim-import" if module == "importer" else f"swgsim-{module}"
    assert lines[0].startswith(f"{prog}: error: broken install: "), lines[0]
    assert broken in lines[0] and "reinstall with bash scripts/quickstart.sh" in lines[0]
    assert not (tmp_path / out).exists()  # nothing written


@pytest.mark.parametrize("kind", ["a folder", "a text file"])
def test_a_store_mlflow_cannot_open_is_refused(tmp_path, kind):
    from learn.tracking.store import check_tracking

    db = tmp_path / "mlflow.db"
    if kind == "a folder":
        db.mkdir()
    else:
        db.write_text("not a database\n" * 100)
    with pytest.raises(ValueError) as e:
        check_tracking(f"sqlite:///{db}", "logger.tracking_uri")
    line = str(e.value)
    assert line.startswith(f"logger.tracking_uri=sqlite:///{db}: ") and "\n" not in line


def test_check_tracking_opens_the_store(tmp_path):
    """The store is opened (its schema created), not only its folder checked."""
    import sqlite3

    from learn.tracking.store import check_tracking

    db = tmp_path / "mlflow.db"
    check_tracking(f"sqlite:///{db}", "tracking_uri")
    tables = {r[0] for r in sqlite3.connect(db).execute(
        "select name from sqlite_master where type='table'")}
    assert "experiments" in tables


def test_a_broken_mlflow_is_found_by_the_tracking_check(tmp_path):
    """A missing library inside MLflow (here cryptography, planted broken) is one line
    naming it from check_tracking, in a fresh process."""
    site = _plant(tmp_path, "cryptography")
    code = ("from learn.tracking.store import check_tracking\n"
            "try:\n"
            f"    check_tracking('sqlite:///{tmp_path}/mlflow.db', 'logger.tracking_uri')\n"
            "except ValueError as e:\n"
            "    print(e)\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(ROOT)])}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=env, timeout=300)
    assert r.stdout.startswith("broken install: mlflow cannot be imported"), r.stdout + r.stderr
    assert "cryptography" in r.stdout


class _HealthOnly(BaseHTTPRequestHandler):
    """A tracking server whose backend store is down: ``/health`` answers 200, the API
    hangs (``api = "hang"``) or answers 500."""

    api = "hang"

    def do_GET(self):  # noqa: N802 - the handler's name
        if self.path == "/health":
            self.send_response(200)
            self.end_headers()
            self.wfile.write(b"OK")
        elif self.api == "hang":
            time.sleep(30)
        else:
            self.send_response(500)
            self.end_headers()

    do_POST = do_GET

    def log_message(self, *args):
        pass


@pytest.mark.parametrize("api, words", [("hang", "does not answer /api/2.0/mlflow/"),
                                        ("500", "answers /api/2.0/mlflow/experiments/search "
                                                "with HTTP 500")])
def test_a_server_that_answers_its_health_check_but_not_its_api_is_refused_at_once(
        api, words):
    """MLflow's client waits 120 s a request and retries 7 times (the audit: over 400 s
    on a hanging API, 256 s on one that answers 500); the check asks once, 5 s."""
    from learn.tracking.store import SERVER_TIMEOUT_S, check_tracking

    handler = type("Handler", (_HealthOnly,), {"api": api})
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    uri = f"http://127.0.0.1:{server.server_address[1]}"
    t0 = time.perf_counter()
    try:
        with pytest.raises(ValueError) as e:
            check_tracking(uri, "logger.tracking_uri")
    finally:
        server.shutdown()
    assert time.perf_counter() - t0 < 2 * SERVER_TIMEOUT_S + 2
    line = str(e.value)
    assert line.startswith(f"logger.tracking_uri={uri}: ") and words in line, line
    assert "\n" not in line


def test_checking_imports_keeps_numpys_floating_point_state():
    # in a fresh interpreter: emlearn sets numpy.seterr(all='raise') when first imported
    code = ("import numpy as np\nfrom learn.tracking.preflight import check_imports\n"
            "before = np.geterr()\ncheck_imports(['emlearn'])\nassert np.geterr() == before\n")
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize(("module", "args", "words"), [
    ("train", ["stored.path=nowhere"], "nowhere is not a data set"),
    ("calibrate", ["measured=nowhere.csv", "out_dir=out"], "'nowhere.csv' does not exist"),
    ("paper", ["run_on=[]"], "run_on must name"),
])
def test_a_bad_input_is_refused_before_the_libraries_are_imported(tmp_path, module, args, words):
    # mlflow planted broken: a bad input is named first, in the second the imports would take
    r = _app(tmp_path, module, args, "mlflow")
    lines = [s for s in r.stderr.splitlines() if s.strip()]
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert words in lines[0] and "broken install" not in lines[0], lines[0]


def test_tracking_store_is_checked_before_any_work(tmp_path, monkeypatch, capsys):
    # the console's entry point in this process, as its command line runs it (run_app; a
    # fresh process per case cost an import of the stack: the planted cases above need one)
    bad = tmp_path / "not_a_db.db"
    bad.write_text("not sqlite")
    code, err = run_app("swgsim-paper", [
        "grid=tiny", f"data_root={tmp_path}/data", f"report_root={tmp_path}/reports",
        f"tracking_uri=sqlite:///{bad}"], tmp_path, monkeypatch, capsys)
    assert code == 2 and f"tracking_uri=sqlite:///{bad}" in err
    assert not (tmp_path / "data").exists() and bad.read_text() == "not sqlite"
    code, err = run_app("swgsim-paper", [
        "grid=tiny", f"data_root={tmp_path}/data",
        "tracking_uri=sqlite:////nowhere/at/all/mlflow.db"], tmp_path, monkeypatch, capsys)
    assert code == 2 and "/nowhere/at/all does not exist" in err
