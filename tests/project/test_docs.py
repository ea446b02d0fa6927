"""The project's own docs: every document and section the code cites exists in the repository.

A *citation* is a project document named in the code: a file name in capitals ending in
``.md`` (``PHYSICS.md``, ``docs/PHYSICS.md``, ``README.md``; generated reports are named in
lower case, ``report.md``, and are not citations; ``docs/STYLE.md``), found anywhere in the
files of ``swgsim/``, ``learn/``, ``swgcli/``, ``scripts/``, ``conf/`` and ``tests/``
(docstrings, comments and strings such as an effect's ``source``) and in ``docs/*.md``.
Each must

* resolve to a file inside the repository: a bare name to ``docs/<name>`` or, failing
  that, ``<name>`` at the repository root; a path relative to the repository root as
  written. Absolute paths, ``~`` and paths leaving the repository are refused: the docs
  must not cite files outside it;
* have every section it cites: ``PHYSICS.md sec. 4``, ``sec. 1, 5``, ``sec. 1 and 4``,
  ``sec. 1-2`` (both ends), ``sec. 3.6`` (a line break or comment marks between name and
  ``sec.`` allowed) must be a numbered heading of that document, ``ARCHITECTURE.md,
  "Calibration loop"`` a heading containing that text.

Also checked: ``docs/PHYSICS.md``'s sections are numbered 1..K without gaps or repeats and
each subsection sits in its section; the sections the code cites hold what the citing
docstrings rely on; relative links in ``docs/*.md`` resolve. The checker itself is run on
planted bad citations, so these tests can fail.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
SCANNED_DIRS = ("swgsim", "learn", "swgcli", "scripts", "conf", "tests")
SUFFIXES = {".py", ".yaml", ".yml", ".sh", ".toml", ".cfg", ".txt"}
THIS_FILE = Path(__file__).resolve()  # holds planted bad citations

# a document name in capitals, optionally with a path; not part of a longer token or URL;
# or any page of docs/ named with its folder (docs/monitor.md)
DOC_RE = re.compile(
    r"(?<![\w./~:-])(?P<path>(?:/|~/|(?:\.\.?/)+)?(?:[\w.-]+/)*[A-Z][A-Z0-9_]*\.md"
    r"|docs/(?:[\w-]+/)*[\w-]+\.md)(?![\w/-])")
# what may stand between a document name and its section: quotes/backticks, comment marks,
# line breaks and an optional comma
_GAP = r"[`'\s#*\]()]*,?[\s#*]*"
SEC_RE = re.compile(_GAP + r"(?:sec(?:tion)?s?\.?|§)\s*"
                    r"(?P<nums>\d+(?:\.\d+)*(?:(?:\s*(?:,|and|&)\s*|[-–])\d+(?:\.\d+)*)*)", re.I)
QUOTED_RE = re.compile(_GAP + r"[\"“](?P<title>[A-Za-z][^\"”\n]*)[\"”]")
HEADING_RE = re.compile(r"^(?P<hashes>#{1,6})\s+(?P<text>.+?)\s*$", re.M)
NUMBERED_RE = re.compile(r"^(?P<num>\d+(?:\.\d+)*)\.?\s+\S")
MD_LINK_RE = re.compile(r"\]\((?P<target>[^)\s]+)\)")


def resolve(cited: str, base: Path = ROOT) -> tuple[Path | None, str | None]:
    """The repository file a citation names, or (None, why not); a path starting with
    ``./`` or ``../`` is relative to ``base``, the folder of the citing file (a page of
    ``docs/`` including ``../README.md``)."""
    if cited.startswith(("/", "~")):
        return None, "is outside the repository (absolute path)"
    if "/" not in cited:
        for cand in (DOCS / cited, ROOT / cited):
            if cand.is_file():
                return cand, None
        return None, f"is neither docs/{cited} nor {cited} at the repository root"
    target = ((base if cited.startswith(".") else ROOT) / cited).resolve()
    if ROOT not in target.parents:
        return None, "is outside the repository"
    if not target.is_file():
        return None, f"does not exist ({target.relative_to(ROOT)})"
    return target, None


def headings(doc: Path) -> list[str]:
    """Heading texts of a markdown document, in order (code blocks skipped)."""
    text = re.sub(r"^```.*?^```", "", doc.read_text(encoding="utf-8"), flags=re.M | re.S)
    return [m["text"] for m in HEADING_RE.finditer(text)]


def section_numbers(doc: Path) -> set[str]:
    """Numbers of the numbered headings (``## 4. ...``, ``### 4.2 ...``) of a document."""
    return {m["num"] for h in headings(doc) if (m := NUMBERED_RE.match(h))}


def _strip_md_links(text: str) -> str:
    return MD_LINK_RE.sub("]()", text)


def citation_problems(text: str, where: str, base: Path = ROOT) -> list[str]:
    """Problems with the document citations in ``text`` (empty if all resolve).

    Parameters
    ----------
    text : str
        File content (for markdown, link targets are checked separately).
    where : str
        Name of the file, for the messages.
    base : Path
        Folder of the file: relative paths (``../README.md``) start there.
    """
    out = []
    for m in DOC_RE.finditer(text):
        cited = m["path"]
        line = text.count("\n", 0, m.start()) + 1
        doc, why = resolve(cited, base)
        if doc is None:
            out.append(f"{where}:{line}: cites {cited}, which {why}")
            continue
        sec = SEC_RE.match(text, m.end())
        if sec:
            have = section_numbers(doc)
            for num in re.findall(r"\d+(?:\.\d+)*", sec["nums"]):
                if num not in have:
                    out.append(f"{where}:{line}: cites {cited} sec. {num}, which has no "
                               f"heading numbered {num} (it has {sorted(have, key=_key)})")
        quoted = QUOTED_RE.match(text, m.end())
        if quoted:
            title = quoted["title"].strip().lower()
            if not any(title in h.lower() for h in headings(doc)):
                out.append(f"{where}:{line}: cites {cited}, \"{quoted['title']}\", which is "
                           "not a heading of it")
    return out


def _key(num: str) -> tuple[int, ...]:
    return tuple(int(x) for x in num.split("."))


def _scanned_files() -> list[Path]:
    files = [p for d in SCANNED_DIRS for p in sorted((ROOT / d).rglob("*"))
             if p.is_file() and p.suffix in SUFFIXES and "__pycache__" not in p.parts
             and p.resolve() != THIS_FILE]
    return files + sorted(DOCS.glob("*.md"))


def _physics_sections() -> dict[str, str]:
    """Top-level section number -> its text (heading and body) of docs/PHYSICS.md."""
    text = (DOCS / "PHYSICS.md").read_text(encoding="utf-8")
    parts = re.split(r"^(?=## )", text, flags=re.M)
    out = {}
    for part in parts:
        m = re.match(r"## (\d+)\.\s", part)
        if m:
            out[m[1]] = part
    return out


# --------------------------------------------------------------------------- the checks
def test_docs_exist():
    for name in ("PHYSICS.md", "ARCHITECTURE.md", "DATASET.md", "STYLE.md"):
        assert (DOCS / name).is_file(), f"docs/{name} is missing"


def test_every_cited_document_and_section_exists():
    files = _scanned_files()
    assert len(files) > 50, f"scanned only {len(files)} files: wrong root {ROOT}?"
    problems, n_cited = [], 0
    for f in files:
        text = f.read_text(encoding="utf-8", errors="replace")
        if f.suffix == ".md":
            text = _strip_md_links(text)
        n_cited += len(DOC_RE.findall(text))
        problems += citation_problems(text, str(f.relative_to(ROOT)), f.parent)
    assert n_cited >= 30, f"found only {n_cited} citations; is the pattern broken?"
    assert not problems, "\n".join(problems)


def test_code_cites_physics_sections():
    """The code cites PHYSICS.md by section (about forty times): the scan must see them."""
    n = 0
    for f in _scanned_files():
        if f.parent == DOCS:
            continue
        text = f.read_text(encoding="utf-8", errors="replace")
        n += sum(1 for m in DOC_RE.finditer(text)
                 if m["path"].endswith("PHYSICS.md") and SEC_RE.match(text, m.end()))
    assert n >= 20, f"only {n} section citations of PHYSICS.md found"


def test_markdown_links_in_docs_resolve():
    problems = []
    for doc in sorted(DOCS.glob("*.md")):
        for m in MD_LINK_RE.finditer(doc.read_text(encoding="utf-8")):
            target = m["target"].split("#")[0]
            if not target or re.match(r"^[a-z]+:", target):  # anchor or URL
                continue
            if target.startswith("auto_examples/"):  # the gallery, made by the docs build
                target = "../examples/" + target.removeprefix("auto_examples/").replace(
                    "index.rst", "README.rst")
            path = (doc.parent / target).resolve()
            if ROOT not in path.parents or not path.exists():
                problems.append(f"docs/{doc.name}: link {m['target']} does not resolve "
                                "inside the repository")
    assert not problems, "\n".join(problems)


def test_physics_numbering_is_consistent():
    """Sections 1..K once each; every subsection a.b inside section a, in order."""
    top, current, subs = [], None, []
    for h in headings(DOCS / "PHYSICS.md"):
        m = NUMBERED_RE.match(h)
        if not m:
            continue
        num = _key(m["num"])
        if len(num) == 1:
            top.append(num[0])
            current, subs = num[0], []
        else:
            assert current == num[0], f"subsection {m['num']} outside section {current}"
            assert not subs or num > subs[-1], f"subsection {m['num']} out of order"
            subs.append(num)
    assert top == list(range(1, len(top) + 1)), f"top-level sections numbered {top}"


# What the citing docstrings rely on each cited section to hold (module: what it cites).
EXPECTED_CONTENT = {
    "1": ("dynamics.py: φ_out = −φ_in/N, α_tooth 20°, J_out seed, ~1 arcmin KE; "
          "measurement.py: ψ = φ_in (1 + 1/N); friction/strain effects: KE harmonics",
          ["pressure angle", "20°", "8.8e-3", "arcmin", "kinematic error", "1 + 1/N",
           "eq. 1"]),
    "2": ("dynamics.py Catalogue, pitch radius; faults.py w0 = module with z_f = 200; "
          "learn/inputs/signals.py ratio N = 100",
          ["25.4", "0.254", "200", "K1", "K3", "0.105", "52", "ratio"]),
    "3": ("flexspline.py: lattice analogy, size-17 strain 2.8e-4, κ shear; "
          "test_flexspline.py: closed forms",
          ["Hrennikoff", "McHenry", "2.8e-4", "κ_s", "closed form", "T / (2π R² t)"]),
    "4": ("sensors.py: bridges (Hoffmann), GF 2.0 constantan, Schuller 2024; "
          "measurement.py: quarter bridge; strain_effects: Godler, Taghirad; "
          "test_chain.py: mV/V of order 0.1",
          ["Hoffmann", "constantan", "Schuller", "Godler", "Taghirad", "quarter bridge",
           "0.1-0.5 mV/V", "2.02"]),
    "5": ("friction_effects.py: temperature, load and direction dependence, gauge "
          "temperature drift; strain_effects.py: offsets, amplifier low-pass with speed",
          ["temperature drift", "offsets", "low-pass", "Stribeck", "presliding", "μ F_n",
           "direction"]),
    "7": ("disturbance.py: eq. (10) ranges the paper does not give",
          ["eq. (10)", "not given", "Table V"]),
}


@pytest.mark.parametrize("num", sorted(EXPECTED_CONTENT))
def test_cited_physics_sections_hold_what_the_code_expects(num):
    why, words = EXPECTED_CONTENT[num]
    text = _physics_sections().get(num)
    assert text is not None, f"docs/PHYSICS.md has no section {num} ({why})"
    missing = [w for w in words if w not in text]
    assert not missing, f"docs/PHYSICS.md sec. {num} lacks {missing} ({why})"


def test_physics_has_no_unfilled_placeholders():
    text = (DOCS / "PHYSICS.md").read_text(encoding="utf-8")
    assert not re.findall(r"\{\{\w+\}\}", text)


# ------------------------------------------------------------------- the checker can fail
# the planted names are assembled at run time, so that this file cites no missing document
MD = ".md"
PLANTED = '''"""Planted citations.

Missing section PHYSICS.md sec. 99, a list PHYSICS.md sec. 1 and 42, a range
docs/PHYSICS.md sec. 2-66, one across a line:
see PHYSICS.md
    sec. 77. A document that does not exist: NOSUCHDOC{md}; outside the repository:
``/work/shared/data/joint_friction/README{md}``, ../ELSEWHERE{md} and ~/NOTES{md}.
A heading that is not there: ARCHITECTURE.md, "No such heading". A lower-case page of
the docs that is not there: docs/nosuchpage{md}; one whose heading is not: docs/monitor.md,
"No such section".
"""
# comment citing docs/PHYSICS.md
# sec. 88
'''.replace("{md}", MD)


def test_checker_reports_planted_bad_citations():
    problems = citation_problems(PLANTED, "planted.py")
    text = "\n".join(problems)
    for needle in ("sec. 99", "sec. 42", "sec. 66", "sec. 77", "sec. 88", "NOSUCHDOC" + MD,
                   "/work/shared/data/joint_friction/README" + MD, "../ELSEWHERE" + MD,
                   "~/NOTES" + MD, "No such heading", "docs/nosuchpage" + MD,
                   "No such section"):
        assert needle in text, f"planted citation {needle!r} not reported:\n{text}"
    assert "sec. 1," not in text and "sec. 2," not in text  # sections 1 and 2 exist
    assert len(problems) == 12, text


def test_checker_accepts_good_citations():
    good = ('"""docs/PHYSICS.md sec. 3.6, PHYSICS.md sec. 1, 5 and STYLE.md; README.md;\n'
            'ARCHITECTURE.md, "Calibration loop"; docs/DATASET.md; lower case report.md,\n'
            'docs/monitor/prognosis.md, "Prognosis"; docs/calibration.md;\n'
            'a URL https://example.org/SOMETHING' + MD + '."""')
    assert citation_problems(good, "good.py") == []
