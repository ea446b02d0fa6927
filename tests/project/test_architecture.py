"""The layout's rules, held by a test (docs/ARCHITECTURE.md, "Floors"): no import cycle
anywhere in the project (imports inside functions included), every package's declared
floors respected, every package within its line budget, no function over 80 lines but
those listed with a reason, the monitor's numeric module constants within their ceiling;
the library's size printed (``pytest -s -k library_size``)."""

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
#: (neither imports the other), the monitor swgmon on learn, the apps of swgcli on top.
FLOORS: dict[str, list[tuple[str, int]]] = {
    "swgsim": [("swgsim.base", 0), ("swgsim.files", 0), ("swgsim.gear", 1),
               ("swgsim.sensing", 2), ("swgsim.datasets", 3), ("swgsim", 4)],
    "swgcal": [("swgcal.split", 0), ("swgcal.periodogram", 0),
               ("swgcal.terms", 0), ("swgcal.core", 1), ("swgcal.diagnose", 2),
               ("swgcal.loop", 3), ("swgcal.discovery", 4), ("swgcal.report", 4),
               ("swgcal.friction", 5), ("swgcal.strain", 5), ("swgcal.thermal", 5),
               ("swgcal.api", 6), ("swgcal", 7)],
    "learn": [("learn.inputs", 0), ("learn.tracking", 0), ("learn.learners", 1),
              ("learn.studies", 2), ("learn.tasks", 3), ("learn.observability", 3),
              ("learn.paper", 4), ("learn.transfer", 5), ("learn", 6)],
    # the blocks of ISO 13374, lowest first (docs/ARCHITECTURE.md, issue 84)
    "swgmon": [("swgmon.detection", 0), ("swgmon.assessment", 1), ("swgmon.prognosis", 2),
               ("swgmon.advisories", 3), ("swgmon.evaluation", 4), ("swgmon.export", 5),
               ("swgmon", 6)],
}
#: Which packages a package may import (besides itself).
USES = {"swgsim": set(), "swgcal": {"swgsim"}, "learn": {"swgsim"},
        "swgmon": {"swgsim", "learn"}, "swgcli": {"swgsim", "swgcal", "learn", "swgmon"}}
MAX_FUNCTION_LINES = 80
#: Lines each package may hold, and the library in all (issue 84: a budget per package in
#: place of a cap per module; sizes follow concepts, a module is as long as its concept).
#: Today's sizes rounded up to the next 500 lines; a package that grows past its budget
#: fails, and its budget moves only in a commit that says why. The issue's targets, to
#: reach by design: swgmon 9000, learn 11000, the library 47500. Moved: swgmon 13500 ->
#: 14000 and all 56000 -> 56500 for the own-joint route (issue 87, +190 lines); swgmon
#: 14000 -> 14100 and all 56500 -> 56700 for issue 85's lives by laws the prognosis does
#: not assume (a growth family, its day, the lot: +107 lines in swgmon, +110 in swgsim);
#: swgmon 14100 -> 14200 and all 56700 -> 56800 for issue 84's NamingConfig (16 tuned
#: numbers as typed fields with ranges, units and sources, plumbed to the apps: +30);
#: swgmon 14200 -> 14300 and all 56800 -> 56950 for issue 84's LawFit, fit_level,
#: PrognosisTargets, max_scale, max_prognoses and curve_hours (24 numeric module
#: constants become typed, logged fields with ranges and sources: +130); swgmon 14300 ->
#: 14500 and all 56950 -> 57150 for issue 84's registry of hypotheses (the naming's four
#: fits as classes of one registry, their evidence in each alarm's report: +210); swgmon
#: 14500 -> 14550 and all 57150 -> 57200 for issue 85's severity track (no relearning
#: after a gear-fault alarm, the severity read unwidened) and the export's limits read
#: from emlearn (+38); swgmon 14550 -> 14610 and all 57200 -> 57260 for issue 85's prior
#: on a crack's Paris m (a grid of laws weighed by their evidence: +56); swgmon 14610 ->
#: 14705 and all 57260 -> 57350 for issue 85's reading curve (the severity regressors'
#: out-of-sample shrinkage inverted, saved with the model and checked: +78; its
#: degenerate case, training gears read alike to the digit, and old pickles: +13);
#: swgmon 14705 -> 14725 and all 57350 -> 57370 for issue 84's last five numeric module
#: constants as typed, logged fields (two chunk sizes, the share buckets, the confidence
#: level of two studies: +20, the buckets' three functions in one place); swgmon 14725 ->
#: 14790 and all 57370 -> 57435 for issue 85's failure history (the lot's failure
#: severities as the prognosis's spread of the threshold, conditioned on survival: +55;
#: it and the chunk logged with the runs, its default's measured why: +3); swgmon 14790 ->
#: 14880 and all 57435 -> 57525 for issue 84's arbitration rule (a Bayes factor with
#: declared priors on an effective number of windows, in place of a tuned median p: +86);
#: swgmon 14880 -> 14885 and all 57525 -> 57530 for issue 85's evaluation time (a track's
#: windows read at once, block by block estimated: +4); learn 11500 -> 11520, swgmon
#: 14885 -> 14920 and all 57530 -> 57630 for issue 85's staged parts (the prognosis's
#: evaluation resumable per held-out instance, the benchmark's design-then-lives stages
#: moved beside the other part machinery and shared: +98); swgmon 14920 -> 14950 and all
#: 57630 -> 57660 for issue 85's calibration per fault (a Mondrian cell per fault with
#: the pooled one as its fallback: +27); swgmon 14950 -> 15280 and all 57660 -> 57990 for
#: issue 85's CV+ (the severity regressors per fold, saved with the model and checked when
#: loaded; each fold's reads through the stream; the CV+ interval, its choice per cell and
#: the quarters' hull shared with the split interval: +323); all 57990 -> 58010 for a
#: stamp copy a worker killed while joining leaves, proved ours by its content (+20);
#: swgmon 15280 -> 15330 and all 58010 -> 58090 for issue 85's lives of at least 100 h (a
#: law drawn again, keyed by its attempt, while its life is shorter: +53; a life's schedule
#: grown by another law and moved to the lot's bank in swgsim: +29); swgmon 15330 -> 15350
#: and all 58090 -> 58110 for issue 84's drift fit on record (its grid's four literals as
#: NamingConfig fields with ranges, units and why: +24); all 58110 -> 58125 for a zombie
#: worker counted as not running (its state read from /proc: +15); swgmon 15350 -> 15430
#: and all 58125 -> 58205 for the benchmark's second protocol (issue 84's targets A-F from
#: a run's two files, declared before its scored run: +80); swgmon 15430 -> 15525 and all
#: 58205 -> 58300 for issue 84's checks (the stuck reading a registered hypothesis the
#: stream asks without an alarm, with its windows and finding, checked: +92); swgmon
#: 15525 -> 15555 and all 58300 -> 58330 for issue 84's advisories by concern (what the
#: monitor tells of a stream, its report, apart from the run: a module's header, +29);
#: swgmon 15555 -> 15580 and all 58330 -> 58355 for issue 84's assessment apart from
#: detection (an alarm named and its severity estimated in naming.py, GearMonitor the
#: detection's scores and alarms: a module's header, +25); learn 11520 -> 11513, swgmon
#: 15580 -> 15521 and all 58355 -> 58280 for what the library wrote twice, merged (the
#: evaluations' two stages and CSVs, a scored run's console line, the candidates' check,
#: the features' summary, the run-in's and re-greasing's Coulomb term apart, -75).
LINE_BUDGETS: dict[str, int] = {"swgsim": 18000, "swgcal": 11500, "learn": 11513,
                                "swgmon": 15521, "swgcli": 2000, "all": 58280}
#: Numeric module constants the monitor may hold (issue 84: at most 10, physical and
#: format constants with sources; a tuned number is a typed config field, logged with
#: every run). Today's count: it moves only down.
MAX_NUMERIC_CONSTANTS = {"swgmon": 10}
#: Functions allowed beyond MAX_FUNCTION_LINES: "path:name" -> why (most are over by
#: their numpydoc docstring, which the style asks for; the code lines follow).
LONG_FUNCTIONS_JUSTIFIED: dict[str, str] = {
    "swgsim/datasets/generate.py:generate": "docstring 38 lines, code 44",
    "learn/inputs/signals.py:build_input": "docstring 39, code 52",
    "learn/learners/nets.py:fine_tune": "docstring 38, code 61",
    "learn/studies/latency.py:measure_latency": "docstring 35, code 53",
    "learn/paper/study.py:paper_study": "docstring 35, code 47",
    "swgsim/gear/thermal.py:network_temperatures": "docstring 36, code 49",
    "learn/studies/protocols.py:make_splits": "docstring 33, code 58",
    "learn/transfer/study.py:run_comparisons": "docstring 53, code 39",
    "learn/tracking/mlflow_runs.py:log_run": "docstring 49, code 40",
    "scripts/bench_generate.py:main": "a benchmark's report, 81 lines: to split",
    "scripts/naming_study.py:main": "a study's report, 83 lines: to split",
    "scripts/paper_sensitivity.py:main": "a study's report, 86 lines: to split",
}


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
    dirs = ("swgsim", "swgcal", "learn", "swgmon", "swgcli", "scripts", "tests")
    return sorted(f for d in dirs for f in (ROOT / d).rglob("*.py"))


def _long_functions() -> dict[str, int]:
    out = {}
    for f in _python_files():
        if f.is_relative_to(ROOT / "tests"):
            continue
        for n in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)):
                size = n.end_lineno - n.lineno + 1
                if size > MAX_FUNCTION_LINES:
                    out[f"{f.relative_to(ROOT)}:{n.name}"] = size
    return out


def test_every_package_within_its_line_budget():
    size = import_graph.library_lines()
    over = {k: (v[1], LINE_BUDGETS[k]) for k, v in size.items() if v[1] > LINE_BUDGETS[k]}
    assert over == {}, "lines over the package's budget (lines, budget)"
    assert set(LINE_BUDGETS) == set(size)  # a new package gets a budget


def _numeric(node: ast.AST) -> bool:
    """A number written in: a literal, its sign, arithmetic of literals, a tuple of them."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, (int, float)) and not isinstance(node.value, bool)
    if isinstance(node, ast.UnaryOp):
        return _numeric(node.operand)
    if isinstance(node, ast.BinOp):
        return _numeric(node.left) and _numeric(node.right)
    return isinstance(node, ast.Tuple) and bool(node.elts) and all(map(_numeric, node.elts))


def numeric_constants(package: str) -> list[str]:
    """``path:NAME`` of each upper-case module-level name assigned a number written in."""
    out = []
    for path in sorted((ROOT / package).rglob("*.py")):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None \
                    and _numeric(node.value):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names = [n.id for t in targets
                         for n in (t.elts if isinstance(t, ast.Tuple) else [t])
                         if isinstance(n, ast.Name) and n.id.lstrip("_").isupper()]
                out += [f"{path.relative_to(ROOT)}:{n}" for n in names]
    return out


def test_the_monitors_numeric_module_constants_within_their_ceiling():
    found = numeric_constants("swgmon")
    assert "swgmon/prognosis/scores.py:PHM08_EARLY" in found  # the count sees them
    assert len(found) <= MAX_NUMERIC_CONSTANTS["swgmon"], found


def test_no_function_over_80_lines_without_a_reason():
    long = _long_functions()
    assert {k: v for k, v in long.items() if k not in LONG_FUNCTIONS_JUSTIFIED} == {}
    assert sorted(set(LONG_FUNCTIONS_JUSTIFIED) - set(long)) == []  # back under: unlist it


def test_library_size_is_counted_and_printed():
    size = import_graph.library_lines()
    n_files = sum(1 for p in import_graph.PACKAGES for _ in (ROOT / p).rglob("*.py"))
    parts = [size[p] for p in import_graph.PACKAGES]
    assert size["all"] == (sum(m for m, _ in parts), sum(n for _, n in parts))
    assert size["all"][0] == n_files
    print("library lines: " + ", ".join(f"{k} {v[1]}" for k, v in size.items()))


def test_no_test_module_imports_another():
    """Set-ups tests share live in fixtures (``conftest.py``) or in the tests' helper
    modules (``data_sets``, ``physics_reference``, ``bad_input``, ``strain_run``,
    ``planted_strain``, ``planted_thermal``, ``real_day``), never in a test module another
    imports."""
    bad = []
    for f in sorted((ROOT / "tests").rglob("*.py")):
        for n in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            names = ([n.module or ""] if isinstance(n, ast.ImportFrom)
                     else [a.name for a in n.names] if isinstance(n, ast.Import) else [])
            bad += [f"{f.relative_to(ROOT)}: {m}" for m in names
                    if m.split(".")[0].startswith("test_") or m.split(".")[0] == "conftest"]
    assert bad == []
