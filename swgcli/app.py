"""How the apps run: typed config, one-line errors, clean stops.

:func:`hydra_app` turns a task function ``task(cfg)`` into a console entry point:

* Hydra composes ``conf/<config_name>.yaml`` on the app's schema (``swgcli.schema``) and
  :func:`swgcli.schema.validate` refuses keys the schema lacks and numbers outside their
  field's range, and :func:`check_out_dirs` output folders given as files, before any
  work;
* every library the app's runs import is resolved next (``needs``,
  :func:`learn.tracking.preflight.check_imports`): a broken install is one line naming the
  package, before any work;
* bad input ends in one line on stderr, ``<prog>: error: <what>``, naming the key or file,
  and exit code 2: Hydra's composition errors (unknown, missing or mistyped keys, unknown
  config options, overrides it cannot parse, with how to quote them), :class:`ValueError`
  (our range and consistency checks, data-set and measured-data errors) and unreadable
  input files; ``HYDRA_FULL_ERROR=1`` shows the traceback instead;
* SIGTERM stops the app as Ctrl-C does (:func:`run`, the one place for every app): the
  exception unwinds (claims closed, temporary files removed), a second signal meanwhile
  is ignored so that the cleanup finishes, progress bars are closed, the worker pool
  (joblib's loky executor) is shut down with its workers killed, and an error a pool
  raises because its workers got the signal too is taken as the stop, not as a bug (the
  workers start with SIGINT blocked, :func:`shield_workers`, so that a terminal's Ctrl-C
  reaches them through the app only); the
  app ends with one line naming what was finished and kept and how a rerun resumes
  (:func:`swgsim.files.ownership.stop_note`), and exit code 130 (SIGINT) or 143
  (SIGTERM);
* anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import dataclasses
import os
import re
import signal
import sys
from collections.abc import Callable, Sequence
from typing import Any

from learn.tracking.preflight import check_imports
from swgcli import CONF_DIR
from swgsim.files.inputs import absolute_path
from swgsim.files.ownership import forget_stops

#: the flags that ask for an app's help (:func:`app_help`)
HELP_FLAGS = ("--help", "-h")


class Terminated(KeyboardInterrupt):
    """Raised in the main thread on SIGTERM, so that cleanup runs as for Ctrl-C."""


_STOPPING: list[int] = []  # the signal that is stopping this process, once received


def _on_signal(signum, frame):  # noqa: ARG001
    """SIGTERM or SIGINT: raise the stop in the main thread, once; a second signal while
    the first unwinds is ignored, so that the cleanup finishes."""
    if _STOPPING:
        return
    _STOPPING.append(signum)
    raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def shield_workers() -> None:
    """Start joblib's workers (and loky's resource tracker) with SIGINT blocked: a
    terminal's Ctrl-C reaches the whole process group, and a worker that gets it prints
    its own KeyboardInterrupt traceback (while importing, or in the middle of a task);
    the app stops them instead (:func:`stop_workers`). SIGTERM still ends a worker
    silently. Wraps loky's ``fork_exec``, once; the mask is set in the spawning thread
    only for the spawn (the child keeps it across exec)."""
    try:
        from joblib.externals.loky.backend import fork_exec as fe
    except ImportError:  # no joblib: no pool
        return
    if getattr(fe.fork_exec, "swg_shielded", False):
        return
    real = fe.fork_exec

    def fork_exec(*args, **kwargs):
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            return real(*args, **kwargs)
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)

    fork_exec.swg_shielded = True  # type: ignore[attr-defined]
    fe.fork_exec = fork_exec


def stop_workers() -> None:
    """Shut down joblib's worker pool (the loky executor), killing its workers, and
    close the progress bars still open: what a stop leaves running otherwise."""
    loky = sys.modules.get("joblib.externals.loky.reusable_executor")
    executor = getattr(loky, "_executor", None) if loky else None
    if executor is not None:
        try:
            executor.shutdown(wait=True, kill_workers=True)
        except Exception:  # noqa: BLE001 - a pool already broken by the signal
            pass
    tqdm = sys.modules.get("tqdm.std")
    for bar in list(getattr(getattr(tqdm, "tqdm", None), "_instances", ()) or ()):
        try:
            bar.close()
        except Exception:  # noqa: BLE001 - a bar of a finished stream
            pass


def stop_line(prog: str, code: int) -> str:
    """The one line a stopped app ends with: how it was stopped, what it kept, how to
    resume (:func:`swgsim.files.ownership.stop_note`)."""
    from swgsim.files.ownership import stop_note

    how = "terminated (SIGTERM)" if code == 143 else "interrupted (SIGINT)"
    note = stop_note()
    return f"{prog}: {how}; " + (note or "nothing was written into an output folder "
                                 "yet; rerun the same command to start again")


def check_out_dirs(cfg: Any, schema: type) -> None:
    """Refuse an output folder given as a file, before any work.

    Every key the schema lists in ``OUT_DIRS`` (e.g. ``out_dir``, ``report_dir``) is
    resolved from the directory the app was started in
    (:func:`swgsim.files.inputs.absolute_path`); the path and every parent that exists must
    be folders.

    Parameters
    ----------
    cfg : omegaconf.DictConfig
        The composed app config.
    schema : dataclass type
        The app's schema; ``OUT_DIRS`` (a class variable) names its output folders.

    Raises
    ------
    ValueError
        ``<key>=<path>: is a file, not a folder`` (or names the file among its parents).
    """
    from pathlib import Path

    from omegaconf import OmegaConf

    for key in getattr(schema, "OUT_DIRS", ()):
        value = OmegaConf.select(cfg, key, default=None)
        if value is None:
            continue
        path = Path(absolute_path(str(value))).expanduser()
        for p in (path, *path.parents):
            if p.is_dir():
                break
            if p.exists() or p.is_symlink():
                where = "" if p == path else f" {p}"
                raise ValueError(f"{key}={value}:{where} is a file, not a folder")


def override_message(override: str, argv: list[str] | None = None) -> str:
    """One line on a command-line override Hydra cannot parse, with how to write it.

    Parameters
    ----------
    override : str
        The override as Hydra got it (one command-line argument).
    argv : list of str, optional
        The command line (default ``sys.argv``), to name the argument before a stray
        word: a value with a space given as two arguments.

    Returns
    -------
    str
        E.g. ``override 'data': not key=value; ...``.
    """
    argv = sys.argv[1:] if argv is None else argv
    key, eq, value = override.partition("=")
    if not eq and not override.startswith(("~", "+")):
        prev = [a for a, b in zip(argv, argv[1:], strict=False) if b == override and "=" in a]
        hint = (f"if it belongs to '{prev[0]}', quote the value with its space as one "
                f"argument: '{prev[0]} {override}'" if prev else
                "a value with a space must be one quoted argument: 'key=a b'")
        return f"override '{override}': not key=value; {hint}"
    if "~" in value:
        home = os.path.expanduser(value) if value.startswith("~") else None
        full = f" ({key}={home})" if home and home != value else ""
        return (f"override '{override}': Hydra reads '~' only as the delete prefix (~key), "
                f"not in a value, and does not expand it; give the full path{full}, or "
                f"quote a literal ~: '{key}=\"{value}\"'")
    return (f"override '{override}': not a valid Hydra override; quote a value with special "
            f"characters (space, ~, =, brackets, quotes): '{key}=\"{value}\"'")


def null_section_message(args: list[str]) -> str:
    """The line for an override into a section that is null in the composed config
    (OmegaConf asserts there, naming no key): the dotted overrides it may be, and which
    config defines the sections that are null without it.

    Parameters
    ----------
    args : list of str
        The command line's arguments after the program.
    """
    dotted = [a.split("=", 1)[0].lstrip("+") for a in args
              if "=" in a and "." in a.split("=", 1)[0]
              and not a.lstrip("+").startswith(("-", "~", "hydra."))]
    where = f" ({', '.join(dotted)})" if dotted else ""
    return (f"an override{where} sets a key inside a section that is null in this config: "
            "select the config that defines the section first (experiment=monitor for "
            "monitor.*, experiment=transfer for transfer.*; a data-set section in a "
            "preset, dataset=...)")


def one_line(exc: BaseException) -> str | None:
    """The one-line message of a bad-input exception, or None for anything else."""
    from hydra.errors import (
        ConfigCompositionException,
        MissingConfigException,
        OverrideParseException,
    )
    from omegaconf.errors import (
        ConfigAttributeError,
        ConfigKeyError,
        MissingMandatoryValue,
        OmegaConfBaseException,
        ValidationError,
    )

    if isinstance(exc, OverrideParseException):
        return override_message(exc.override)
    cause = exc.__cause__ if isinstance(exc, ConfigCompositionException) else exc
    if isinstance(cause, (ConfigAttributeError, ConfigKeyError)):
        key = getattr(cause, "full_key", None) or "?"
        typ = getattr(cause, "object_type", None)
        allowed = ""
        if typ is not None and dataclasses.is_dataclass(typ):  # ClassVars are no keys
            allowed = "; allowed: " + ", ".join(f.name for f in dataclasses.fields(typ))
        return f"{key}: unknown key{allowed}"
    if isinstance(cause, MissingMandatoryValue):
        key = getattr(cause, "full_key", None) or "?"
        return f"{key}: missing value (give {key}=...)"
    if isinstance(cause, ValidationError):
        key = getattr(cause, "full_key", None) or "?"
        m = re.match(r"Value '?(-?\d+)'? \(int\) is incompatible with type hint 'float'",
                     cause.msg)
        if m:  # OmegaConf converts no int inside a nested list of floats
            return (f"{key}: {m.group(1)} is an integer where a float is required (OmegaConf "
                    f"checks the numbers of nested lists strictly); write it with a decimal "
                    f"point: {m.group(1)}.0")
        return f"{key}: {cause.msg.splitlines()[0]}"
    if isinstance(cause, OmegaConfBaseException):
        key = getattr(cause, "full_key", None)
        msg = str(getattr(cause, "msg", cause)).splitlines()[0]
        return f"{key}: {msg}" if key else msg
    m = re.search(r"full_key: (\S+)", str(cause))  # OmegaConf's own error while merging
    if m and isinstance(cause, AttributeError) and "'NoneType'" in str(cause):
        key = m.group(1)
        return (f"{key}: is null in this preset, and OmegaConf cannot merge a whole section "
                f"into a null one from the command line; set {key} in a data-set preset "
                "(conf/dataset/*.yaml, e.g. tiny_life.yaml) and select it with dataset=...")
    if isinstance(cause, AssertionError) and re.match(r"Unexpected type.*None", str(cause)):
        return null_section_message(sys.argv[1:])
    if isinstance(exc, (ConfigCompositionException, MissingConfigException)):
        text = str(exc).split("Config search path:")[0]
        lines = [s.strip() for s in text.splitlines() if s.strip()]
        first = re.sub(r"^In '[^']*': ", "", lines[0]) if lines else type(exc).__name__
        options = [s for s in lines[1:] if not s.endswith(":")]
        return first + (f"; available: {', '.join(options)}" if options else "")
    if isinstance(exc, ValueError):
        return str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if isinstance(exc, (FileNotFoundError, IsADirectoryError, NotADirectoryError,
                        PermissionError)):
        return f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": ")
    return None


def run(entry: Callable[[], Any], prog: str) -> Any:
    """Run a Hydra entry point with one-line errors and clean stops (module docstring)."""
    user_full = os.environ.get("HYDRA_FULL_ERROR") == "1"
    os.environ["HYDRA_FULL_ERROR"] = "1"  # Hydra raises; we decide how to report
    os.environ["SWG_USER_FULL_ERROR"] = "1" if user_full else "0"
    _STOPPING.clear()
    forget_stops()
    shield_workers()
    previous = {signal.SIGTERM: signal.signal(signal.SIGTERM, _on_signal)}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not ignored
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, _on_signal)
    try:
        return entry()
    except KeyboardInterrupt as e:
        _stop(prog, 143 if isinstance(e, Terminated) else 130)
    except Exception as e:  # noqa: BLE001 - sorted into stops, bad input and bugs below
        if _STOPPING:  # a worker pool's error because its workers got the signal too
            _stop(prog, 143 if _STOPPING[0] == signal.SIGTERM else 130)
        msg = one_line(e)
        if msg is None or user_full:
            raise
        print(f"{prog}: error: {msg}", file=sys.stderr)
        sys.exit(2)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if not user_full:
            os.environ.pop("HYDRA_FULL_ERROR", None)


def _stop(prog: str, code: int) -> None:
    """End a stopped app: no further signal, the pool and bars stopped, one line."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    stop_workers()
    print(stop_line(prog, code), file=sys.stderr, flush=True)
    sys.exit(code)


def config_groups(cfg: Any) -> dict[str, list[str]]:
    """The config groups an app accepts and their options, as its ``--help`` lists them.

    A group is accepted when the app's config composes it (Hydra's
    ``hydra.runtime.choices``, the key as a user overrides it: ``dataset``,
    ``dataset@datasets.bench``); Hydra's own groups (``hydra/...``) are left to
    ``--hydra-help``, and a group the app's defaults do not name is refused by its schema.

    Parameters
    ----------
    cfg : omegaconf.DictConfig
        The app's config composed with ``return_hydra_config=True``.

    Returns
    -------
    dict of str to list of str
        Override key -> option names (``conf/<group>/*.yaml`` and the schemas registered
        in Hydra's ConfigStore), sorted.
    """
    from hydra.core.config_store import ConfigStore

    repo = ConfigStore.instance().repo
    keys = [k for k in cfg.hydra.runtime.choices if not k.startswith("hydra/")]
    groups = {}
    for key in keys:
        group = key.split("@")[0]
        names = {n.removesuffix(".yaml") for n in repo.get(group, {})}
        folder = os.path.join(CONF_DIR, group)
        if os.path.isdir(folder):
            names |= {f.removesuffix(".yaml") for f in os.listdir(folder)
                      if f.endswith(".yaml")}
        groups[key] = sorted(names)
    return groups


def app_help(config_name: str, overrides: list[str]) -> str:
    """An app's ``--help``: its header, the config groups it accepts
    (:func:`config_groups`), its config with the command line's overrides, its footer.

    Hydra's own help lists every group in the search path, those an app refuses among
    them, and takes seconds to find their options; this one composes the config once.

    Parameters
    ----------
    config_name : str
        Primary config in ``conf/``.
    overrides : list of str
        The command line's overrides (``key=value``), applied to the config shown.

    Raises
    ------
    hydra.errors.ConfigCompositionException, OverrideParseException
        An override Hydra refuses (reported in one line by :func:`run`).
    """
    from hydra import compose, initialize_config_dir
    from omegaconf import OmegaConf

    with initialize_config_dir(config_dir=CONF_DIR, version_base="1.3"):
        cfg = compose(config_name=config_name, overrides=overrides,
                      return_hydra_config=True)
    groups = config_groups(cfg)
    listed = "\n".join(f"{k}: {', '.join(v)}" for k, v in groups.items()) or "(none)"
    shown = OmegaConf.to_yaml(OmegaConf.masked_copy(cfg, [k for k in cfg if k != "hydra"]))
    head, foot = cfg.hydra.help.header, cfg.hydra.help.footer
    return (f"{head}\n== Configuration groups ==\nCompose your configuration from those "
            f"groups (group=option)\n\n{listed}\n\n== Config ==\nOverride anything in "
            f"the config (foo.bar=value)\n\n{shown}\n{foot}")


def hydra_app(config_name: str, schema: type, prog: str, needs: Sequence[str] = (),
              inputs: Callable[[Any], Any] | None = None):
    """Decorator: a task function ``task(cfg)`` as a console entry point ``main()``.

    Parameters
    ----------
    config_name : str
        Primary config in ``conf/`` (``generate``, ``paper``, ``train``, ``calibrate``).
    schema : dataclass type
        The app's schema (:mod:`swgcli.schema`), checked before the task runs.
    prog : str
        Program name for messages.
    needs : sequence of str
        The libraries the app's runs import (its module's ``NEEDS``), resolved after the
        config is checked and before the task starts
        (:func:`learn.tracking.preflight.check_imports`): a broken install is one line
        naming the package, exit 2, before any work.
    inputs : callable, optional
        ``inputs(cfg)``: the app's checks of what it reads and where it writes (a file or
        data set that must exist, a folder it must own), run after the schema and before
        the libraries in ``needs`` are imported, so that a bad input is refused in about a
        second rather than after seconds of imports; it must not import those libraries.

    Returns
    -------
    callable
        Decorator returning ``main()``; the task stays importable for tests as
        ``main.task``.
    """
    import hydra

    from swgcli.schema import validate

    def deco(task: Callable[[Any], Any]) -> Callable[[], Any]:
        failed: list[BaseException] = []
        home = {"pid": os.getpid()}  # the process of entry(); a launcher's job may run elsewhere

        @hydra.main(version_base="1.3", config_path=CONF_DIR, config_name=config_name)
        def _hydra_main(cfg):
            try:
                validate(cfg, schema)
                check_out_dirs(cfg, schema)
                if inputs is not None:
                    inputs(cfg)
                check_imports(needs)  # a broken install found before any work
                return task(cfg)
            except Exception as e:  # noqa: BLE001
                if _STOPPING or one_line(e) is None or os.getpid() != home["pid"] \
                        or os.environ.get("SWG_USER_FULL_ERROR") == "1":
                    raise  # in a job of another process (submitit): the job must fail
                failed.append(e)  # reported once by main(), not by Hydra's job runner
                return None

        def entry():
            from swgcli.schema import check_renamed

            args = sys.argv[1:]
            check_renamed([a for a in args if not a.startswith("-")], config_name)
            if any(a in HELP_FLAGS for a in args):  # Hydra's own takes seconds (app_help)
                print(app_help(config_name, [a for a in args if a not in HELP_FLAGS]))
                return
            failed.clear()  # a run in the same process reports its own error
            home["pid"] = os.getpid()
            _hydra_main()
            if failed:
                raise failed[0]

        def main() -> Any:
            return run(entry, prog)

        main.task = task  # type: ignore[attr-defined]
        main.schema = schema  # type: ignore[attr-defined]
        main.__doc__ = f"Console entry point of {prog} (config conf/{config_name}.yaml)."
        return main

    return deco
