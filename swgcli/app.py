"""How the apps run: typed config, one-line errors, clean stops.

:func:`hydra_app` turns a task function ``task(cfg)`` into a console entry point:

* Hydra composes ``conf/<config_name>.yaml`` on the app's schema (``swgcli.schema``) and
  :func:`swgcli.schema.validate` refuses keys the schema lacks and numbers outside their
  field's range, and :func:`check_out_dirs` output folders given as files, before any
  work;
* bad input ends in one line on stderr, ``<prog>: error: <what>``, naming the key or file,
  and exit code 2: Hydra's composition errors (unknown, missing or mistyped keys, unknown
  config options, overrides it cannot parse, with how to quote them), :class:`ValueError`
  (our range and consistency checks, data-set and measured-data errors) and unreadable
  input files; ``HYDRA_FULL_ERROR=1`` shows the traceback instead;
* SIGTERM stops the app as Ctrl-C does: the exception unwinds, worker processes are
  stopped and temporary files removed; exit code 130 (SIGINT) or 143 (SIGTERM);
* anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import os
import re
import signal
import sys
from collections.abc import Callable
from typing import Any

from swgcli import CONF_DIR


class Terminated(KeyboardInterrupt):
    """Raised in the main thread on SIGTERM, so that cleanup runs as for Ctrl-C."""


def _on_sigterm(signum, frame):  # noqa: ARG001
    raise Terminated()


def absolute_path(path: str) -> str:
    """``path`` relative to the directory the app was started in (Hydra changes into its
    run folder); unchanged outside a Hydra run (tests calling a task directly)."""
    from hydra.utils import to_absolute_path

    try:
        return to_absolute_path(path)
    except ValueError:  # outside a Hydra run
        return path


def check_out_dirs(cfg: Any, schema: type) -> None:
    """Refuse an output folder given as a file, before any work.

    Every key the schema lists in ``OUT_DIRS`` (e.g. ``out_dir``, ``report_dir``) is
    resolved from the directory the app was started in (:func:`absolute_path`); the
    path and every parent that exists must be folders.

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
        if typ is not None and hasattr(typ, "__dataclass_fields__"):
            allowed = "; allowed: " + ", ".join(typ.__dataclass_fields__)
        return f"{key}: unknown key{allowed}"
    if isinstance(cause, MissingMandatoryValue):
        key = getattr(cause, "full_key", None) or "?"
        return f"{key}: missing value (give {key}=...)"
    if isinstance(cause, ValidationError):
        key = getattr(cause, "full_key", None) or "?"
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
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        return entry()
    except Terminated:
        print(f"{prog}: terminated", file=sys.stderr)
        sys.exit(143)
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        sys.exit(130)
    except Exception as e:  # noqa: BLE001 - sorted into bad input and bugs below
        msg = one_line(e)
        if msg is None or user_full:
            raise
        print(f"{prog}: error: {msg}", file=sys.stderr)
        sys.exit(2)
    finally:
        signal.signal(signal.SIGTERM, previous)
        if not user_full:
            os.environ.pop("HYDRA_FULL_ERROR", None)


def hydra_app(config_name: str, schema: type, prog: str):
    """Decorator: a task function ``task(cfg)`` as a console entry point ``main()``.

    Parameters
    ----------
    config_name : str
        Primary config in ``conf/`` (``generate``, ``paper``, ``train``, ``calibrate``).
    schema : dataclass type
        The app's schema (:mod:`swgcli.schema`), checked before the task runs.
    prog : str
        Program name for messages.

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

        @hydra.main(version_base="1.3", config_path=CONF_DIR, config_name=config_name)
        def _hydra_main(cfg):
            try:
                validate(cfg, schema)
                check_out_dirs(cfg, schema)
                return task(cfg)
            except Exception as e:  # noqa: BLE001
                if one_line(e) is None or os.environ.get("SWG_USER_FULL_ERROR") == "1":
                    raise
                failed.append(e)  # reported once by main(), not by Hydra's job runner
                return None

        def entry():
            from swgcli.schema import check_renamed

            check_renamed([a for a in sys.argv[1:] if not a.startswith("-")], config_name)
            failed.clear()  # a run in the same process reports its own error
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
