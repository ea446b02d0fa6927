"""The project's import graph and function lengths, from the source (no imports run).

Prints modules and lines per package (the library's size, :func:`library_lines`: the
``.py`` files of swgsim, swgcal, learn, swgmon and swgcli; the architecture test prints it too),
the import cycles between modules (strongly
connected components of the graph of intra-project imports, TYPE_CHECKING imports
included), imports that climb back up a declared layer, and the longest functions.

    python scripts/import_graph.py            # the summary
    python scripts/import_graph.py --top 20   # more long functions
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("swgsim", "swgcal", "learn", "swgmon", "swgcli")
#: Lower layers never import higher ones (the apps sit on top).
LAYERS = {"swgsim": 0, "swgcal": 1, "learn": 1, "swgmon": 2, "swgcli": 3}


def modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the project's packages."""
    out = {}
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*.py")) if (ROOT / pkg).is_dir() else ():
            parts = list(f.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = f
    return out


def _top_level(tree: ast.Module):
    """The import statements a module runs when it is imported: not those inside
    functions or classes, nor under ``if TYPE_CHECKING:``."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, ast.If):
            if "TYPE_CHECKING" not in ast.unparse(node.test):
                stack.extend(node.body + node.orelse)
        elif isinstance(node, ast.Try):
            stack.extend(node.body + node.orelse + node.finalbody
                         + [n for h in node.handlers for n in h.body])
        elif isinstance(node, ast.With):
            stack.extend(node.body)


def imports(name: str, path: Path, known: set[str], top_level: bool = False) -> set[str]:
    """Project modules that ``name`` imports (absolute and relative, any depth; with
    ``top_level``, only the imports run at import time)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_pkg = path.name == "__init__.py"
    base = name.split(".") if is_pkg else name.split(".")[:-1]
    found = set()
    for node in (_top_level(tree) if top_level else ast.walk(tree)):
        if isinstance(node, ast.Import):
            cands = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                root = base[: len(base) - node.level + 1]
                mod = ".".join(root + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            cands = [mod] + [f"{mod}.{a.name}" for a in node.names]
        else:
            continue
        for c in cands:
            while c and c not in known:
                c = c.rpartition(".")[0]
            if c and c != name:
                found.add(c)
    return found


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def library_lines(mods: dict[str, Path] | None = None) -> dict[str, tuple[int, int]]:
    """Package -> (modules, lines) of the library's ``.py`` files, and ``"all"``."""
    per_pkg = {k: [0, 0] for k in (*PACKAGES, "all")}
    for m, f in (modules() if mods is None else mods).items():
        n = len(f.read_text(encoding="utf-8").splitlines())
        for key in (m.split(".")[0], "all"):
            per_pkg[key][0] += 1
            per_pkg[key][1] += n
    return {k: (v[0], v[1]) for k, v in per_pkg.items()}


def long_functions(mods: dict[str, Path], top: int) -> list[tuple[int, str]]:
    """(lines, 'file:line name') of the longest functions outside tests."""
    rows = []
    for f in mods.values():
        for n in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)):
                rows.append((n.end_lineno - n.lineno + 1,
                             f"{f.relative_to(ROOT)}:{n.lineno} {n.name}"))
    return sorted(rows, reverse=True)[:top]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=10, help="long functions to list")
    args = ap.parse_args(argv)
    mods = modules()
    graph = {m: imports(m, f, set(mods)) for m, f in mods.items()}
    print("modules and lines per package:")
    for pkg, (n, lines) in library_lines(mods).items():
        print(f"  {pkg:<8s} {n:>3d} modules {lines:>6d} lines")
    cyc = cycles(graph)
    print(f"import cycles: {len(cyc)}")
    for c in cyc:
        print("  " + " <-> ".join(c))
    up = [(m, d) for m, ds in graph.items() for d in ds
          if LAYERS[d.split(".")[0]] > LAYERS[m.split(".")[0]]
          or (m.split(".")[0], d.split(".")[0]) in {("swgcal", "learn"), ("learn", "swgcal")}]
    print(f"imports up a layer: {len(up)}")
    for m, d in up:
        print(f"  {m} -> {d}")
    lengths = long_functions(mods, args.top)
    n80 = sum(1 for f in mods.values() for n in ast.walk(ast.parse(f.read_text()))
              if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
              and n.end_lineno - n.lineno + 1 > 80)
    print(f"functions over 80 lines: {n80}; longest:")
    for n, where in lengths:
        print(f"  {n:>4d}  {where}")


if __name__ == "__main__":
    main()
