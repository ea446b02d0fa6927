"""Sphinx configuration of the documentation site (``bash scripts/quickstart.sh docs``).

Built offline (no intersphinx, nothing fetched) with warnings as errors. Sources: the
Markdown pages of ``docs/`` (MyST), the API reference generated from the numpydoc
docstrings of ``swgsim``, ``learn``, ``swgmon``, ``swgcal`` and ``swgcli`` (autosummary, recursive),
and the gallery of ``examples/`` (sphinx-gallery, run on the tiny presets at each build).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "swg-monitor"
author = "swg-monitor contributors"
copyright = "swg-monitor contributors, MIT licence"  # noqa: A001 (Sphinx's name)

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_static", "screenshots", "figures", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip", "**.codeobj.json",
                    "sg_execution_times.rst"]
templates_path = ["_templates"]
suppress_warnings: list[str] = []
nitpicky = False

# --------------------------------------------------------------------------- documents
#: Topic pages written by others that may or may not be in this checkout, each with the
#: page that stands in when it is absent (``None``: left out when absent).
OPTIONAL_PAGES = {"TRANSFER": "learners_transfer", "OWN_JOINT": None}
#: Pages placed in a toctree by name; every other ``docs/*.md`` joins "More documents".
PLACED = {"index", "getting_started", "guide", "apps", "simulation", "PHYSICS", "DATASET",
          "paper_study", "learners_transfer", "TRANSFER", "OWN_JOINT", "observability",
          "monitor", "calibration", "EXPORT", "scale_out", "development", "ARCHITECTURE",
          "STYLE"}


#: The pages whose toctrees hold markers.
MARKED = ("guide", "development")


def _present(name: str) -> bool:
    return (DOCS / f"{name}.md").is_file()


for _doc, _standin in OPTIONAL_PAGES.items():
    if _present(_doc) and _standin:
        exclude_patterns.append(f"{_standin}.md")


def _toc_entries(marker: str) -> str:
    """What a toctree marker of ``index.md`` stands for in this checkout."""
    if marker == "TRANSFER":
        return "TRANSFER" if _present("TRANSFER") else "learners_transfer"
    if marker == "OWN_JOINT":
        return "OWN_JOINT" if _present("OWN_JOINT") else ""
    if marker == "MORE":  # documents added to docs/ by others: listed, never orphaned
        more = [p.stem for p in sorted(DOCS.glob("*.md")) if p.stem not in PLACED]
        if not more:
            return ""
        return "## More documents\n\n```{toctree}\n:maxdepth: 1\n\n" + "\n".join(more) + "\n```"
    raise ValueError(f"docs/conf.py: unknown toctree marker @{marker}@")


def _fill_markers(app, docname: str, source: list[str]) -> None:
    """Toctree markers (a line ``@NAME@``) replaced by the pages of this checkout; links
    to the repository's README (``../README.md``, read on GitHub) to the site's front
    page, which says what the README says; links to a stand-in page to the page it
    stands in for, when that is present."""
    if docname in MARKED:
        source[0] = re.sub(r"^@(\w+)@$", lambda m: _toc_entries(m[1]), source[0],
                           flags=re.M)
    if "/" not in docname:
        source[0] = source[0].replace("](../README.md)", "](index.md)")
    for doc, standin in OPTIONAL_PAGES.items():  # links to a stand-in go to the page itself
        if standin and _present(doc):
            source[0] = source[0].replace(f"{standin}.md)", f"{doc}.md)")


# ------------------------------------------------------------------------------ MyST
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3
# docs/*.md link to the repository's README and code by relative path (they are read on
# GitHub too); such links point to the files, not into the site
myst_all_links_external = False

# ---------------------------------------------------------------- API: autosummary, numpydoc
autosummary_generate = True
autosummary_imported_members = False
autosummary_ignore_module_all = True
autodoc_default_options = {"show-inheritance": False}
autodoc_typehints = "none"  # numpydoc's Parameters say the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# ------------------------------------------------------------------------------ gallery
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",  # plot_<n>_...: the reading order
    "abort_on_example_error": True,
    "show_memory": False,
    "plot_gallery": "True",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "capture_repr": (),
    "line_numbers": False,
    "min_reported_time": 1,
    "show_signature": False,
}

# ------------------------------------------------------------------------------- HTML
html_theme = "pydata_sphinx_theme"
html_title = "swg-monitor"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_show_sourcelink = False
html_copy_source = False
html_last_updated_fmt = None
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "show_version_warning_banner": False,
    "check_switcher": False,
}
html_sidebars = {"index": [], "getting_started": [], "auto_examples/index": []}


#: A cross-reference written as a relative import, ``:mod:`.data``` (``~`` allowed).
_RELATIVE_REF = re.compile(r":(?P<role>mod|func|class|data|attr|meth|exc):`(?P<tilde>~?)"
                           r"(?P<dots>\.+)(?P<rest>[A-Za-z_][\w.]*)`")


def _absolute(package: str, dots: str, rest: str) -> str | None:
    """The dotted name a relative reference stands for, as Python's relative import
    would read it from ``package``; None when it names nothing importable."""
    import importlib

    parts = package.split(".")
    if len(dots) > 1:
        parts = parts[: len(parts) - len(dots) + 1]
    name = ".".join([*parts, rest])
    head, tail = name, []
    while head:  # the longest importable module, then attributes
        try:
            obj = importlib.import_module(head)
        except ImportError:
            head, _, last = head.rpartition(".")
            tail.insert(0, last)
            continue
        for attr in tail:
            if not hasattr(obj, attr):
                return None
            obj = getattr(obj, attr)
        return name
    return None


def _resolve_relative_refs(app, what, name, obj, options, lines: list[str]) -> None:
    """The project writes module references as relative imports (``:mod:`.effects```,
    relative to the module's package); Sphinx would search every module ending in
    ``.effects``. Each is pointed at the module the import would give, its text kept."""
    import importlib

    modname = name if what == "module" else getattr(obj, "__module__", None)
    if not isinstance(modname, str) or not modname:
        return
    try:
        mod = importlib.import_module(modname)
    except ImportError:
        return
    package = modname if hasattr(mod, "__path__") else modname.rpartition(".")[0]

    def repl(m: re.Match) -> str:
        target = _absolute(package, m["dots"], m["rest"])
        if target is None:
            return m[0]
        text = m["rest"].rpartition(".")[2] if m["tilde"] else m["dots"] + m["rest"]
        return f":{m['role']}:`{text} <{target}>`"

    lines[:] = [_RELATIVE_REF.sub(repl, line) for line in lines]


def _skip_member(app, what, name, obj, skip, options):
    """scikit-learn's generated metadata-routing setters (``set_fit_request``, ...) belong
    to scikit-learn's documentation, not this project's."""
    if re.fullmatch(r"set_\w+_request", name):
        return True
    return None


def setup(app) -> None:
    app.connect("source-read", _fill_markers)
    app.connect("autodoc-skip-member", _skip_member)
    app.connect("autodoc-process-docstring", _resolve_relative_refs)
