"""Fixtures of the apps' bad-input tests: one tiny life, generated once per test run and
shared by the files that spoil copies of it or feed it to the monitor."""

from __future__ import annotations

from pathlib import Path

import pytest
from data_sets import built_once

from swgcli import dataset_preset


@pytest.fixture(scope="session")
def life(tmp_path_factory) -> Path:
    """A finished tiny life of gear 3 (2 h, a window every 2 min, an eccentric WG from
    1.5 h on), as swgsim-generate writes it; read it, or spoil a copy."""
    from swgsim.datasets import generate as gen

    cfg = dataset_preset("tiny_life")
    cfg["gears"] = [g for g in cfg["gears"] if g["id"] == 3]
    cfg["life"].update(hours=2.0, commissioning_h=1.0, interval_min=2.0)
    cfg["life"]["fault"]["onset_h"] = 1.5
    return built_once(tmp_path_factory, "life", lambda out: gen.generate(
        cfg, out, n_jobs=1, progress=False))
