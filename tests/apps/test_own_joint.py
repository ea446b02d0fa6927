"""docs/OWN_JOINT.md's three commands, as written there, from a CSV to a verdict: a
simulated life written as a logger's CSV, imported, a diagnosis model made for its
acquisition (``swgsim-train experiment=own_joint``, at a tiny training design here), the
stream through ``swgsim-monitor``; a model for another acquisition is refused naming that
command."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest
import yaml

import swgcli.importer  # noqa: F401  (registers import_schema)
from swgcli import compose_app
from swgsim.datasets.recording_table import stream_table

DOC = Path(__file__).parents[2] / "docs" / "OWN_JOINT.md"
#: A tiny training design (the test's time), added to the documented command.
TINY = ["own_joint.study.commissioning_h=1.0", "own_joint.study.train_healthy_h=0.5",
        "own_joint.study.train_fault_h=0.25", "own_joint.study.train_variants=1",
        "own_joint.study.faults=[eccentric_wg]"]


def documented() -> list[list[str]]:
    """The commands of the page's block between ``own-joint:begin`` and ``own-joint:end``."""
    block = re.search(r"<!-- own-joint:begin -->\n```bash\n(.*?)```", DOC.read_text(), re.S)
    return [shlex.split(line) for line in block.group(1).splitlines() if line.strip()]


@pytest.fixture(scope="module")
def life(tiny_bench):
    """Gear 3 of tiny_life (8 h, commissioning 4 h, an eccentric WG of severity 0.1 from
    6 h) as a stream."""
    from swgsim.datasets.life import LifeSimulator, life_dataset
    from swgsim.datasets.schedule import FaultOnset, LifeConfig

    p, banks = tiny_bench
    cfg = LifeConfig(hours=8.0, commissioning_h=4.0,
                     fault=FaultOnset("eccentric_wg", 6.0, 0.1, position_deg=180.0))
    return life_dataset(LifeSimulator(p, 3, cfg, banks[3]))


def test_the_pages_commands_go_from_a_csv_to_a_verdict(life, tmp_path, monkeypatch):
    from swgcli.importer import run_import
    from swgcli.tasks import run_train
    from swgmon.advisories.task import run_monitor_app

    df, mapping = stream_table(life)
    monkeypatch.chdir(tmp_path)
    df.to_csv("joint.csv", index=False)
    Path("joint.yaml").write_text(yaml.safe_dump(mapping))
    (imp, train, mon) = documented()
    assert [imp[0], train[0], mon[0]] == ["swgsim-import", "swgsim-train", "swgsim-monitor"]
    run_import(compose_app("import", [*imp[1:], "progress=false"]))
    made = run_train(compose_app("train", [*train[1:], "~logger", *TINY]))
    card = json.loads(Path(made["card"]).read_text())
    acq = card["training"][0]["acquisition"]
    assert acq["sample_rate_hz"] == life.attrs["sample_rate_hz"]
    assert acq["window_s"] == pytest.approx(life.sizes["time"] / life.attrs["sample_rate_hz"])
    assert (acq["n_in_rpm"], acq["t_out_nm"]) == ([4000.0], [7.0, 70.0])
    assert card["classes"] == ["healthy", "eccentric_wg"]
    out = run_monitor_app(compose_app("monitor", [*mon[1:], "~logger"]))
    assert Path("reports/joint/summary.json").is_file()
    faults = [a["fault"] for a in out["alarms"]]
    assert faults and set(faults) == {"eccentric_wg"}, faults  # the planted fault, named

    # a model for another window: refused, naming the command that makes one that fits
    other = run_train(compose_app("train", [
        "experiment=own_joint", "~logger", "own_joint.window_s=0.12",
        "own_joint.sample_rate_hz=10000", "own_joint.n_in_rpm=[4000]",
        "own_joint.t_out_nm=[7,70]",
        "own_joint.out=models/other", *TINY]))
    with pytest.raises(ValueError) as e:
        run_monitor_app(compose_app("monitor", [
            "stream=data/joint", f"diagnosis_model={other['model']}", "out_dir=reports/x",
            "~logger"]))
    line = str(e.value)
    assert "windows of 0.06 s" in line and line.endswith(
        "swgsim-train experiment=own_joint "
        f"own_joint.stream={tmp_path / 'data' / 'joint'}"), line


def test_bad_own_joint_keys_are_refused_before_any_work(tmp_path):
    from swgcli.tasks import run_train

    for args, named in ((["own_joint.dataset=tiny"], "own_joint.dataset='tiny'; allowed: "
                         "['bench', 'robot_joint']"),
                        (["own_joint.n_in_rpm=[9000]"], "n_in_rpm"),
                        (["own_joint.window_s=-1"], "own_joint.window_s"),
                        ([f"own_joint.stream={tmp_path}"], f"own_joint.stream: {tmp_path}")):
        with pytest.raises(ValueError) as e:
            run_train(compose_app("train", ["experiment=own_joint", "~logger",
                                            f"own_joint.out={tmp_path}/m", *args]))
        assert named in str(e.value), str(e.value)
    assert not (tmp_path / "m.skops").exists()
