"""MLflow tracking stores: opening one, checking it can be written, its experiments.

Every process opens a store through :func:`tracking_client`: MLflow creates or migrates
an SQLite store's schema when a process first opens it, and two processes doing so at
once break it for one of them, so the first opening in a process holds the store's lock
``<database file>.lock`` (``filelock``; waited for up to 120 s).

The default tracking URI is ``sqlite:///<repo root>/mlflow.db`` (MLflow 3's database
store; its file store is deprecated): ``MLFLOW_TRACKING_URI`` wins if set, as in MLflow
itself. Artifacts of a ``sqlite:///`` store go to ``mlruns/<experiment>/`` beside the
database file (rather than MLflow's default ``./mlruns`` in the working directory); a
server URI keeps the server's artifact store. Browse with ``mlflow ui --backend-store-uri
sqlite:///mlflow.db``.
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Iterator
from contextlib import closing, contextmanager
from pathlib import Path

from learn.tracking.preflight import import_failure
from learn.tracking.provenance import repo_root

#: How long a process waits for another one creating or migrating an SQLite store.
STORE_LOCK_TIMEOUT_S = 120.0
#: How long the check before any work waits for each answer of a tracking server [s]; it
#: asks once (MLflow's own client waits 120 s a request and retries 7 times: a server
#: whose backend store is down would hold the app for minutes before the first job).
SERVER_TIMEOUT_S = 5.0
#: What the check asks a tracking server: that it is up, and that its API answers.
SERVER_PROBES = ("/health", "/api/2.0/mlflow/experiments/search?max_results=1")
_OPENED: set[str] = set()  # stores this process opened (schema created or checked)


def default_tracking_uri() -> str:
    """``MLFLOW_TRACKING_URI`` if set, else ``sqlite:///<repo root>/mlflow.db``."""
    env = os.environ.get("MLFLOW_TRACKING_URI")
    return env if env else f"sqlite:///{repo_root() / 'mlflow.db'}"


def _artifact_location(tracking_uri: str, experiment: str) -> str | None:
    if not tracking_uri.startswith("sqlite:///"):
        return None
    db = Path(tracking_uri.removeprefix("sqlite:///"))
    safe = re.sub(r"[^\w.-]+", "_", experiment)
    return (db.resolve().parent / "mlruns" / safe).as_uri()


def check_tracking(tracking_uri: str | None = None, key: str = "tracking_uri") -> str:
    """Check that an MLflow store can be written and opened, before any work is done.

    After the checks of the file or folder, the store is opened as a run will open it
    (:func:`tracking_client`: MLflow imported, an SQLite store's schema created or
    checked, one query made), so that a broken MLflow install (a library it imports
    missing) or a store MLflow cannot read is found before the first job.

    Parameters
    ----------
    tracking_uri : str, optional
        Default :func:`default_tracking_uri`.
    key : str
        Config key named in messages.

    Returns
    -------
    str
        The URI.

    Raises
    ------
    ValueError
        One line naming ``key`` and the URI: an SQLite store whose folder is missing or
        not writable, or whose file is not an SQLite database; a local folder store that
        is not writable; an HTTP server whose health check or API does not answer within
        :data:`SERVER_TIMEOUT_S`, or answers with an error (asked once each, no retries);
        a store MLflow fails to open (its error's first line).
    learn.tracking.preflight.BrokenInstall
        MLflow (or a library it imports) cannot be imported: one line naming it.
    """
    import sqlite3

    uri = tracking_uri or default_tracking_uri()
    if uri.startswith("sqlite:///"):
        db = Path(uri.removeprefix("sqlite:///"))
        folder = db.parent
        if not folder.is_dir():
            raise ValueError(f"{key}={uri}: folder {folder} does not exist")
        if not os.access(folder, os.W_OK) or (db.exists() and not os.access(db, os.W_OK)):
            raise ValueError(f"{key}={uri}: {db if db.exists() else folder} is not writable")
        if db.exists():
            try:
                with closing(sqlite3.connect(f"file:{db}?mode=ro", uri=True)) as con:
                    con.execute("select name from sqlite_master limit 1").fetchall()
            except sqlite3.DatabaseError as e:
                raise ValueError(f"{key}={uri}: {db} is not an SQLite database ({e})") from None
    elif uri.startswith(("http://", "https://")):
        _ask_server(uri, key)
    else:
        folder = Path(uri.removeprefix("file://"))
        probe = folder if folder.exists() else folder.parent
        if not probe.is_dir() or not os.access(probe, os.W_OK):
            raise ValueError(f"{key}={uri}: {probe} is not a writable folder")
    _open(uri, key)
    return uri


def _ask_server(uri: str, key: str) -> None:
    """Ask a tracking server each of :data:`SERVER_PROBES` once, within
    :data:`SERVER_TIMEOUT_S`; one line naming what failed."""
    import urllib.error
    import urllib.request

    for probe in SERVER_PROBES:
        what = probe.split("?")[0]
        try:
            urllib.request.urlopen(uri.rstrip("/") + probe, timeout=SERVER_TIMEOUT_S).close()
        except urllib.error.HTTPError as e:
            raise ValueError(f"{key}={uri}: the tracking server answers {what} with HTTP "
                             f"{e.code} ({e.reason}); is its backend store up?") from None
        except OSError as e:  # refused, unreachable, or no answer in time
            raise ValueError(f"{key}={uri}: the tracking server does not answer {what} "
                             f"within {SERVER_TIMEOUT_S:g} s ({e})") from None


@contextmanager
def _one_short_request() -> Iterator[None]:
    """MLflow's HTTP client asks once and waits :data:`SERVER_TIMEOUT_S` while inside."""
    keys = {"MLFLOW_HTTP_REQUEST_MAX_RETRIES": "0",
            "MLFLOW_HTTP_REQUEST_TIMEOUT": str(int(SERVER_TIMEOUT_S))}
    before = {k: os.environ.get(k) for k in keys}
    os.environ.update(keys)
    try:
        yield
    finally:
        for k, v in before.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _open(uri: str, key: str) -> None:
    """Open the store as a run will (:func:`tracking_client`); one line on failure. A
    server's store is opened with one short request (:func:`_one_short_request`)."""
    try:
        import mlflow  # noqa: F401 - its import is what a broken install breaks
    except Exception as e:  # noqa: BLE001 - any failure at import is a broken install
        raise import_failure("mlflow", e) from None
    try:
        with _one_short_request():
            tracking_client(uri, key)
    except ValueError:
        raise
    except ImportError as e:  # a store plugin or driver MLflow imports when opening
        raise import_failure("mlflow", e) from None
    except Exception as e:  # noqa: BLE001 - MLflow's and SQLAlchemy's errors, many types
        first = (str(e).strip().splitlines() or [type(e).__name__])[0]
        raise ValueError(f"{key}={uri}: MLflow cannot open the store "
                         f"({type(e).__name__}: {first[:300]})") from None


@contextmanager
def store_lock(tracking_uri: str, key: str = "tracking_uri",
               timeout_s: float = STORE_LOCK_TIMEOUT_S) -> Iterator[None]:
    """Hold the lock of an SQLite store, ``<database file>.lock``, while it is opened.

    Parameters
    ----------
    tracking_uri : str
        A ``sqlite:///`` URI gets the lock; any other URI none (a server or a folder
        store creates nothing that two processes could race on).
    key : str
        Config key named in messages.
    timeout_s : float
        How long to wait for another process holding the lock.

    Raises
    ------
    ValueError
        One line naming ``key`` and the URI if the lock is not had within ``timeout_s``.
    """
    db = tracking_uri.removeprefix("sqlite:///").split("?")[0]
    if not tracking_uri.startswith("sqlite:///") or db in ("", ":memory:"):
        yield
        return
    from filelock import FileLock, Timeout

    lock = FileLock(f"{db}.lock", thread_local=False)
    try:
        lock.acquire(timeout=timeout_s)
    except Timeout:
        raise ValueError(f"{key}={tracking_uri}: another process has held {db}.lock for over "
                         f"{timeout_s:g} s (creating or migrating the store); wait for it "
                         f"to finish or choose another {key}") from None
    try:
        yield
    finally:
        lock.release()


def tracking_client(tracking_uri: str | None = None, key: str = "tracking_uri"):
    """An :class:`mlflow.MlflowClient` on a store; the one way a process opens a store.

    The first time in a process, the client is created and its first query made (MLflow
    creates or migrates the schema of a new SQLite store then) under :func:`store_lock`,
    so that processes starting together on a fresh store all succeed.

    Parameters
    ----------
    tracking_uri : str, optional
        Default :func:`default_tracking_uri`.
    key : str
        Config key named in messages.

    Returns
    -------
    mlflow.MlflowClient

    Raises
    ------
    ValueError
        See :func:`store_lock`.
    """
    import mlflow

    quiet_mlflow()
    uri = tracking_uri or default_tracking_uri()
    if uri in _OPENED:
        return mlflow.MlflowClient(uri)
    with store_lock(uri, key):
        client = mlflow.MlflowClient(uri)
        client.search_experiments(max_results=1)
    _OPENED.add(uri)
    return client


def quiet_mlflow() -> None:
    """Keep MLflow's own INFO messages (database set-up, migrations) off the console.

    MLflow logs through its logger ``mlflow`` with a handler of its own; its warnings and
    errors still show, except SQLAlchemy's deprecation of the ``noload`` loader strategy
    (MLflow's store, not ours to fix) and the one that ``mlflow.sklearn`` repeats for every
    model saved in the cloudpickle format, the format
    :meth:`learn.tracking.mlflow_runs.TrackedRun.log_model` chooses (and records in the
    model's tag ``serialization_format``; its docstring says why).
    """
    import warnings

    warnings.filterwarnings("ignore", message="The ``noload`` loader strategy is deprecated",
                            category=DeprecationWarning)
    lg = logging.getLogger("mlflow")
    if lg.getEffectiveLevel() < logging.WARNING:
        lg.setLevel(logging.WARNING)
    sk = logging.getLogger("mlflow.sklearn")
    if not any(isinstance(f, _PickleWarningFilter) for f in sk.filters):
        sk.addFilter(_PickleWarningFilter())


class _PickleWarningFilter(logging.Filter):
    """Drop ``mlflow.sklearn``'s per-model warning about the (cloud)pickle format."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "pickle or cloudpickle format" not in record.getMessage()


def get_experiment_id(client, experiment: str) -> str:
    """Id of MLflow experiment ``experiment``, created if absent.

    Parameters
    ----------
    client : mlflow.MlflowClient
    experiment : str
        Experiment name.

    Returns
    -------
    str
    """
    from mlflow.exceptions import MlflowException

    exp = client.get_experiment_by_name(experiment)
    if exp is not None:
        return exp.experiment_id
    try:
        return client.create_experiment(
            experiment, artifact_location=_artifact_location(client.tracking_uri, experiment)
        )
    except MlflowException:  # created meanwhile by a parallel job
        exp = client.get_experiment_by_name(experiment)
        if exp is None:
            raise
        return exp.experiment_id
