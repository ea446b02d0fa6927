"""The one reader of a user's YAML (swgsim.base.user_yaml), held by the cases of issue 43:
a key given twice is refused naming the key, the file and both lines (cause 9), and a
YAML alias bomb is refused by what it expands to, before it is built, in a short line
(cause 7a); through the importer's mapping as well."""

from __future__ import annotations

import time

import pytest
import yaml

from swgsim.base.user_yaml import MAX_MESSAGE_CHARS, clip, load_user_yaml, user_yaml
from swgsim.datasets.recording_mapping import read_mapping

#: 9 levels of 9 aliases each: 9**9 (387 million) values from a few hundred bytes.
BOMB = "a: &a [x,x,x,x,x,x,x,x,x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{','.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(8))


def test_a_key_given_twice_refused_naming_key_file_and_lines(tmp_path):
    p = tmp_path / "map.yaml"
    p.write_text("time: time_s\ncommissioning_h: 1.0\nspeed: n\ncommissioning_h: 2.0\n")
    with pytest.raises(ValueError, match=rf"^mapping {p}: line 4: key 'commissioning_h' "
                       r"given twice in one mapping \(first at line 2\)"):
        user_yaml(p, "mapping")


@pytest.mark.parametrize("text, line", [
    ("bridges:\n  unit: counts\n  unit: mV/V\n", 3),  # nested
    ("operating_points: {points: [[1, 2]], points: [[3, 4]]}\n", 1),  # flow, one line
])
def test_a_key_twice_refused_at_any_depth(text, line):
    with pytest.raises(ValueError, match=rf"line {line}: key '\w+' given twice"):
        load_user_yaml(text, "x.yaml")


def test_what_yaml_allows_still_reads():
    """Merge keys may override what they merge; a few aliases are fine; empty is None."""
    text = "base: &b {unit: counts, n: 1}\nbridges:\n  <<: *b\n  n: 2\nalso: [*b, *b]\n"
    got = load_user_yaml(text)
    assert got == yaml.safe_load(text) and got["bridges"] == {"unit": "counts", "n": 2}
    assert load_user_yaml("") is None and load_user_yaml("# nothing\n") is None


def test_an_alias_bomb_refused_before_it_is_built(tmp_path):
    assert len(BOMB.encode()) < 1000
    p = tmp_path / "map.yaml"
    p.write_text(BOMB)
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=r"line \d+: expands to more than 1000000 values "
                       r"\(YAML aliases") as info:
        user_yaml(p, "mapping")
    assert time.perf_counter() - t0 < 2.0 and len(str(info.value)) < MAX_MESSAGE_CHARS
    with pytest.raises(ValueError, match=r"expands to more than 1000000 values"):
        read_mapping(p)  # the importer's mapping reads through it


def test_a_recursive_alias_refused():
    with pytest.raises(ValueError, match=r"an alias inside the node it names"):
        load_user_yaml("a: &a [1, *a]\n")


def test_the_importers_mapping_refuses_a_key_twice(tmp_path):
    p = tmp_path / "map.yaml"
    p.write_text("operating_points:\n  points: [[1500, 10]]\ncommissioning_h: 0.5\n"
                 "commissioning_h: 5\n")
    with pytest.raises(ValueError, match=r"map.yaml: line 4: key 'commissioning_h' given "
                       r"twice"):
        read_mapping(p)


def test_messages_quoting_a_users_values_are_clipped(tmp_path):
    """A value of 100 000 characters where a mapping is wanted: one short line."""
    p = tmp_path / "map.yaml"
    p.write_text("operating_points:\n  points: [[1500, 10]]\ncommissioning_h: 0.5\n"
                 f"time: [{', '.join(['x'] * 50_000)}]\n")
    with pytest.raises(ValueError) as info:
        read_mapping(p)
    msg = str(info.value)
    assert len(msg) <= MAX_MESSAGE_CHARS and "\n" not in msg and msg.startswith("mapping")
    assert clip("a\nb") == "a b"
