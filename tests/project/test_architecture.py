"""The layout's rules, held by a test (docs/ARCHITECTURE.md, "Floors"): no import cycle
anywhere in the project (imports inside functions included), every package's declared
floors respected, no module over 700 lines, no function over 100 lines."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import import_graph  # noqa: E402  (the import graph from the source, no module run)

#: Each package's floors, lowest first: a unit (a sub-package or module, by its dotted
#: prefix; the longest matching prefix counts) imports only units on lower floors, and
#: itself. The packages: swgsim on the ground, swgcal and learn beside each other on it
#: (neither imports the other), the apps of swgcli on top.
FLOORS: dict[str, list[tuple[str, int]]] = {
    "swgsim": [("swgsim.base", 0), ("swgsim.files", 0), ("swgsim.gear", 1),
               ("swgsim.sensing", 2), ("swgsim.datasets", 3), ("swgsim", 4)],
    "swgcal": [("swgcal.options", 0), ("swgcal.split", 0), ("swgcal.periodogram", 0),
               ("swgcal.terms", 0), ("swgcal.core", 1), ("swgcal.diagnose", 2),
               ("swgcal.loop", 3), ("swgcal.discovery", 4), ("swgcal.report", 4),
               ("swgcal.friction", 5), ("swgcal.strain", 5), ("swgcal.thermal", 5),
               ("swgcal.api", 6), ("swgcal", 7)],
    "learn": [("learn.inputs", 0), ("learn.tracking", 0), ("learn.learners", 1),
              ("learn.monitor", 2), ("learn.studies", 3), ("learn.export", 3),
              ("learn.reports", 4), ("learn.tasks", 5), ("learn", 6)],
}
#: Which packages a package may import (besides itself).
USES = {"swgsim": set(), "swgcal": {"swgsim"}, "learn": {"swgsim"},
        "swgcli": {"swgsim", "swgcal", "learn"}}
MAX_MODULE_LINES = 700
MAX_FUNCTION_LINES = 100
#: Functions allowed beyond MAX_FUNCTION_LINES: "path:name" -> why. Empty.
LONG_FUNCTIONS_JUSTIFIED: dict[str, str] = {}


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    mods = import_graph.modules()
    return {m: import_graph.imports(m, f, set(mods)) for m, f in mods.items()}


def unit(module: str) -> tuple[str, int] | None:
    """The floor unit of a module (longest declared prefix) and its floor."""
    floors = FLOORS.get(module.split(".")[0], [])
    hits = [(u, f) for u, f in floors if module == u or module.startswith(u + ".")]
    return max(hits, key=lambda h: len(h[0])) if hits else None


def test_no_import_cycle(graph):
    assert import_graph.cycles(graph) == []


def test_packages_import_only_those_below(graph):
    bad = [f"{m} -> {d}" for m, ds in graph.items() for d in ds
           if d.split(".")[0] != m.split(".")[0]
           and d.split(".")[0] not in USES[m.split(".")[0]]]
    assert bad == []


def test_every_module_of_a_floored_package_has_a_floor(graph):
    assert [m for m in graph if m.split(".")[0] in FLOORS and unit(m) is None] == []


def test_declared_floors_respected(graph):
    bad = []
    for m, ds in graph.items():
        um = unit(m)
        for d in ds:
            ud = unit(d)
            if um and ud and d.split(".")[0] == m.split(".")[0] and ud[0] != um[0] \
                    and ud[1] >= um[1]:
                bad.append(f"{m} (floor {um[1]}) -> {d} (floor {ud[1]})")
    assert bad == []


def test_floors_name_existing_units():
    mods = set(import_graph.modules())
    missing = [u for fl in FLOORS.values() for u, _ in fl
               if not any(m == u or m.startswith(u + ".") for m in mods)]
    assert missing == []


def _python_files() -> list[Path]:
    dirs = ("swgsim", "swgcal", "learn", "swgcli", "scripts", "tests")
    return sorted(f for d in dirs for f in (ROOT / d).rglob("*.py"))


def test_no_module_over_700_lines():
    long = {str(f.relative_to(ROOT)): n for f in _python_files()
            if (n := len(f.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES}
    assert long == {}


def test_no_function_over_100_lines():
    long = []
    for f in _python_files():
        if f.is_relative_to(ROOT / "tests"):
            continue
        for n in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)):
                size = n.end_lineno - n.lineno + 1
                key = f"{f.relative_to(ROOT)}:{n.name}"
                if size > MAX_FUNCTION_LINES and key not in LONG_FUNCTIONS_JUSTIFIED:
                    long.append(f"{key} ({size})")
    assert long == []


def test_the_checker_finds_a_planted_cycle_and_a_floor_breach(tmp_path):
    """The rules can fail: a planted cycle and an import up a floor are found."""
    g = {"swgsim.gear.a": {"swgsim.gear.b"}, "swgsim.gear.b": {"swgsim.gear.a"},
         "swgsim.gear.c": {"swgsim.datasets.plan"}, "swgsim.datasets.plan": set()}
    assert import_graph.cycles(g) == [["swgsim.gear.a", "swgsim.gear.b"]]
    um, ud = unit("swgsim.gear.c"), unit("swgsim.datasets.plan")
    assert ud[1] >= um[1] and ud[0] != um[0]


# ------------------------------------------------------------- the architecture page
DOC = ROOT / "docs" / "ARCHITECTURE.md"


def _apps() -> set[str]:
    import tomllib

    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    return set(scripts)


def _presets() -> set[str]:
    return {f.stem for f in (ROOT / "conf" / "dataset").glob("*.yaml")}


def test_architecture_names_every_app_and_preset():
    import re

    text = DOC.read_text(encoding="utf-8")
    named_apps = set(re.findall(r"`(swgsim-[a-z]+)`", text))
    assert _apps() - named_apps == set(), "apps missing from docs/ARCHITECTURE.md"
    presets = text.split("Data-set presets (`conf/dataset/`):", 1)[1].split("\n\n", 1)[0]
    listed = set(re.findall(r"`([a-z_]+)`", presets))
    assert listed == _presets()


def test_everything_the_architecture_names_exists():
    import re

    text = DOC.read_text(encoding="utf-8")
    missing = [p for p in re.findall(r"`((?:swgsim|learn|swgcal|swgcli|tests|scripts)/"
                                     r"[\w/]+\.py)`", text) if not (ROOT / p).is_file()]
    for pkg, rows in (("swgsim", r"\| `((?:base|files|gear|sensing|datasets)/[\w/]+\.py)`"),):
        missing += [f"{pkg}/{m}" for m in re.findall(rows, text)
                    if not (ROOT / pkg / m).is_file()]
    table = text.split("### `learn/`", 1)[1].split("### `swgcli/`", 1)[0]
    pkg = None
    for line in table.splitlines():
        cells = [c.strip() for c in line.split("|")[1:-1]]
        if len(cells) < 3 or cells[0].startswith("---") or cells[0] == "package":
            continue
        pkg = cells[0].strip("`/") or pkg
        missing += [f"learn/{pkg}/{m}" for m in re.findall(r"`(\w+\.py)`", cells[1])
                    if not (ROOT / "learn" / pkg / m).is_file()]
    dotted = re.findall(r"`((?:swgsim|learn|swgcal)(?:\.\w+)+)`", text)
    import importlib

    for d in dotted:
        parts = d.split(".")
        for k in range(len(parts), 0, -1):  # the longest module prefix, then attributes
            try:
                obj = importlib.import_module(".".join(parts[:k]))
            except ImportError:
                continue
            for a in parts[k:]:
                obj = getattr(obj, a, None)
            if obj is None:
                missing.append(d)
            break
    assert missing == []
