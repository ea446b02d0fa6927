"""The README's Python example runs as written and does what its text says.

The README holds one fenced ``python`` block, between the markers
``<!-- readme-example:start -->`` and ``<!-- readme-example:end -->`` (the documentation
site includes the same lines, docs/getting_started.md). It is run here in a temporary
folder, as a user would paste it: a diagnosis model trained on simulated lives of gears 1
and 2 of the tiny bench grid, gear 3's 8-h life (an eccentric WG from 6 h on) written by
the generator, and the monitor over it. What it prints must be an alarm after the onset,
naming the eccentric WG. The README also keeps its promise of at most 15 lines.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"
BLOCK_RE = re.compile(r"<!-- readme-example:start -->\n```python\n(?P<code>.*?)```\n"
                      r"<!-- readme-example:end -->", re.S)


def readme_example() -> str:
    """The code of the README's Python example (its only fenced python block)."""
    text = README.read_text(encoding="utf-8")
    assert text.count("```python") == 1, "README.md should hold one fenced python block"
    m = BLOCK_RE.search(text)
    assert m, "README.md: the python block is not between the readme-example markers"
    return m["code"]


def test_readme_example_is_short():
    assert len(readme_example().splitlines()) <= 15


def test_readme_example_runs_and_alarms_after_the_onset(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the example writes into a temporary folder, none here
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(readme_example(), str(README), "exec"), {"__name__": "readme"})
    printed = out.getvalue()
    hours = [float(h) for h in re.findall(r"Alarm\(hour=([0-9.]+)", printed)]
    assert hours, f"the example printed no alarm: {printed!r}"
    assert 6.0 <= hours[0] <= 7.0, printed  # the tiny_life preset's onset is at 6 h
    assert "fault='eccentric_wg'" in printed, printed
    assert list(tmp_path.iterdir()) == []  # the working folder (a clone's root) stays clean
