"""No input poisons a result: NaN and infinity are refused in every float of a data-set
config (by rule, not by key), no shard is written with a non-finite signal, and a shard
whose content contradicts the schema is refused on load, each in one line naming the key,
or the file and the variable (a manifest contradicting its shards:
tests/apps/test_bad_data_sets.py)."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from bad_input import load_message, small_cfg
from data_sets import make_synthetic, write_dataset
from omegaconf import OmegaConf

from swgcli import compose_app, dataset_preset
from swgsim.base.typed import NONFINITE, allowed, check_finite, check_keys, check_range, check_tree
from swgsim.datasets import generate as gen
from swgsim.datasets import schema as dsio
from swgsim.datasets.schedule import DutyPoint, FaultOnset, LifeConfig

NAN, INF = float("nan"), float("inf")


def _amplifier(noise: float) -> dict:
    amp = dataset_preset("tiny_bench")["acquisition"]
    amp["amplifier"]["noise_uv_rms"] = noise
    return amp


# ------------------------------------------------------------------ the config
CONFIG_CASES = [  # (edit of small_cfg(), full key, value): keys at every depth
    (lambda c: c["sensors"].update(grid_length_mm=NAN), "dataset.sensors.grid_length_mm", NAN),
    (lambda c: c["sensors"].update(gauge_factor=INF), "dataset.sensors.gauge_factor", INF),
    (lambda c: c["chain"].update(settle_s=NAN), "dataset.chain.settle_s", NAN),
    (lambda c: c["chain"].update(ecc_load_share=-INF), "dataset.chain.ecc_load_share", -INF),
    (lambda c: c["mesh"].update(aspect=NAN), "dataset.mesh.aspect", NAN),
    (lambda c: c["load"].update(j_out_kgm2=INF), "dataset.load.j_out_kgm2", INF),
    (lambda c: c["operating_points"].update(t_out_nm=[39.0, NAN]),
     "dataset.operating_points.t_out_nm[1]", NAN),
    (lambda c: c["variants"]["eccentric_wg"].update(severities=[INF]),
     "dataset.variants.eccentric_wg.severities[0]", INF),
    (lambda c: c["gears"][1].update(ke_extra=[{"order": 3, "amp_rad": 1e-5, "phase_rad": NAN}]),
     "dataset.gears[1].ke_extra[0].phase_rad", NAN),
    (lambda c: c.update(sensor_effects=[{"name": "offset",
                                         "params": {"offset_mvv": [0, 0, NAN, 0, 0]}}]),
     "dataset.sensor_effects[0].params.offset_mvv[2]", NAN),
    (lambda c: c.update(acquisition=_amplifier(NAN)),
     "dataset.acquisition.amplifier.noise_uv_rms", NAN),
    (lambda c: c.update(life={"hours": 2.0, "commissioning_h": 1.0,
                              "fault": {"fault": "eccentric_wg", "onset_h": 1.0,
                                        "growth": "points", "points": [[1.5, NAN]]}}),
     "dataset.life.fault.points[0][1]", NAN),
]


@pytest.mark.parametrize("edit, key, value", CONFIG_CASES, ids=[c[1] for c in CONFIG_CASES])
def test_nonfinite_config_values_are_refused_before_any_work(tmp_path, edit, key, value):
    cfg = small_cfg()
    edit(cfg)
    out = tmp_path / "never"
    with pytest.raises(ValueError) as info:
        gen.generate(cfg, out, progress=False)
    assert str(info.value) == f"{key} must be a finite number, got {value}"
    assert not out.exists()


def test_nan_from_the_command_line_and_from_yaml_is_refused(tmp_path):
    from swgcli.generate import run_generate

    out = tmp_path / "never"
    cfg = compose_app("generate", ["dataset=tiny", "dataset.sensors.r_pairs_mm=nan",
                                   f"out_dir={out}", "progress=false"])
    with pytest.raises(ValueError, match=r"^dataset\.sensors\.r_pairs_mm must be a finite "
                                         r"number, got nan$"):
        run_generate(cfg)
    yaml = OmegaConf.to_container(OmegaConf.create("chain: {window_s: .inf}\n"))
    cfg = small_cfg()
    cfg["chain"].update(yaml["chain"])
    with pytest.raises(ValueError, match=r"^dataset\.chain\.window_s must be a finite number, "
                                         r"got inf$"):
        gen.generate(cfg, out, progress=False)
    assert not out.exists()


@pytest.mark.parametrize("life, key", [
    (LifeConfig(hours=NAN), "dataset.life.hours"),
    (LifeConfig(hours=4, commissioning_h=1, duty=[DutyPoint(2000.0, 7.0, INF)]),
     "dataset.life.duty[0].dwell_min"),
    (LifeConfig(hours=4, commissioning_h=1,
                fault=FaultOnset("eccentric_wg", 2.0, 0.1, position_deg=NAN)),
     "dataset.life.fault.position_deg"),
], ids=["hours", "dwell_min", "position_deg"])
def test_check_life_refuses_nonfinite_values_naming_the_key(life, key):
    with pytest.raises(ValueError, match=rf"^{re.escape(key)} must be a finite number"):
        check_tree(life, "dataset.life")


def test_check_finite_walks_every_container_and_honours_the_field_metadata():
    @dataclasses.dataclass
    class Part:
        cut_off_hz: float = dataclasses.field(default=INF, metadata={NONFINITE: "inf: none"})
        gains: tuple = (1.0, np.float32(1.0))
        table: dict = dataclasses.field(default_factory=lambda: {"a": [1, 2.0]})
        grid: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((2, 3)))
        note: str = "nan"
        count: int = 10**400
        optional: float | None = None

    check_finite(Part(), "part")  # metadata, strings, huge ints, None: accepted
    for change, key in ((dict(gains=(1.0, np.float32(NAN))), r"part\.gains\[1\]"),
                        (dict(table={"a": [1, -INF]}), r"part\.table\.a\[1\]"),
                        (dict(grid=np.array([[0.0, 0.0, 0.0], [0.0, NAN, 0.0]])),
                         r"part\.grid\[1, 1\]")):
        with pytest.raises(ValueError, match=rf"^{key} must be a finite number, got -?(nan|inf)$"):
            check_finite(Part(**change), "part")



def test_a_range_with_a_unit_reads_as_check_range_writes_it():
    @dataclasses.dataclass
    class Part:
        life_h: float = dataclasses.field(default=1.0, metadata=allowed(
            0.0, 1e5, "after the onset", lo_open=True, unit="h"))

    with pytest.raises(ValueError) as by_hand:
        check_range(-1.0, 0.0, 1e5, "part.life_h", "h", lo_open=True, why="after the onset")
    for refuse in (lambda: check_tree(Part(life_h=-1.0), "part"),
                   lambda: check_keys({"life_h": -1.0}, Part, "part")):
        with pytest.raises(ValueError) as e:
            refuse()
        assert str(e.value) == str(by_hand.value) == (
            "part.life_h must lie in (0, 100000] h (after the onset), got -1.0")


def test_a_root_config_named_empty_names_its_keys_alone():
    @dataclasses.dataclass
    class Inner:
        gain: float = dataclasses.field(default=1.0, metadata=allowed(0.0, None, lo_open=True))

    @dataclasses.dataclass
    class Root:
        inner: Inner = dataclasses.field(default_factory=Inner)
        table: dict = dataclasses.field(default_factory=lambda: {"a": 1.0})

    for bad, words in ((Root(Inner(0.0)), "inner.gain must lie in (0, inf), got 0.0"),
                       (Root(Inner(NAN)), "inner.gain must be a finite number, got nan"),
                       (Root(table={"a": INF}), "table.a must be a finite number, got inf")):
        with pytest.raises(ValueError) as e:
            check_tree(bad, "")
        assert str(e.value) == words

# ------------------------------------------------------------------ writing
def test_write_shard_refuses_nonfinite_signals_before_writing(tmp_path):
    ds = make_synthetic(gears=(1,), n_variants=1, ops=((2000.0, 7.0),), n_time=64)
    ds["strain_signal"].values[0, 2, :3] = NAN
    f = tmp_path / "shard.nc"
    with pytest.raises(ValueError, match=rf"shard {f}: strain_signal holds 3 non-finite "
                                         r"value\(s\) \(NaN or infinity\) of \d+; refused"):
        dsio.write_shard(ds, f)
    assert list(tmp_path.iterdir()) == []


def test_generation_never_finalises_a_data_set_with_a_nonfinite_signal(tmp_path, monkeypatch):
    import swgsim.datasets.generate as generation

    simulate = generation.simulate_shard

    def poisoned(*args, **kwargs):
        ds, n = simulate(*args, **kwargs)
        ds["strain_signal"].values[:, 1] = INF  # a bridge that is 100 % infinite
        return ds, n

    monkeypatch.setattr(generation, "simulate_shard", poisoned)
    out = tmp_path / "ds"
    with pytest.raises(ValueError, match=r"gear1_n4000rpm\.nc: strain_signal holds \d+ "
                                         "non-finite"):
        gen.generate(small_cfg(), out, n_jobs=1, progress=False)
    assert not (out / dsio.MANIFEST).exists() and not list(out.glob("*.nc"))


# ------------------------------------------------------------------ loading
def _manifest(folder: Path) -> dict:
    return json.loads((folder / dsio.MANIFEST).read_text())


def _rewrite_shard(folder: Path, edit) -> Path:
    """Edit the first shard's content and record its new SHA-256, as a faulty writer that
    hashes what it wrote would; returns the shard's path."""
    m = _manifest(folder)
    name = sorted(m["shards"])[0]
    f = folder / name
    with xr.open_dataset(f, engine="h5netcdf") as ds:
        ds = edit(ds.load())
    ds.to_netcdf(f, engine="h5netcdf")  # not write_shard: it would refuse a NaN
    m["shards"][name]["sha256"] = dsio.sha256_file(f)
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    return f


def _set(var: str, index, value):
    def edit(ds):
        ds[var].values[index] = value
        return ds
    return edit


@pytest.mark.parametrize("edit, words", [
    (_set("strain_signal", (0, 2, slice(0, 10)), NAN),
     ["strain_signal", "10 non-finite value(s)"]),
    (_set("strain_signal", (3, 0, 5), -INF), ["strain_signal", "1 non-finite value(s)"]),
    (lambda ds: ds.assign_coords(time=np.where(np.arange(ds.sizes["time"]) == 7, NAN,
                                                ds.time.values)), ["time", "1 non-finite"]),
    (_set("fault", 4, "bogus_fault"), ["variable fault", "'bogus_fault' (1 sample(s))",
                                       "not a class of the schema"]),
    (lambda ds: ds.drop_vars("efficiency"), ["variable efficiency is missing"]),
    (lambda ds: ds.assign(gear=ds.gear.astype(str)), ["variable gear has dtype"]),
    (_set("strain_signal", (2, 1, 3), 1e30), ["strain_signal of sample 2 reaches 1e+30 mV/V",
                                              "allowed |s| <= 10 mV/V"]),
], ids=["nan_signal", "inf_signal", "nan_time", "unknown_label", "dropped_variable",
        "mistyped_variable", "signal_beyond_a_bridge"])
def test_load_refuses_a_shard_with_bad_content_naming_file_and_variable(copy_of, edit, words):
    folder = copy_of()
    f = _rewrite_shard(folder, edit)
    msg = load_message(folder)
    assert f"shard {f}" in msg
    for w in words:
        assert w in msg


def test_a_data_set_larger_than_the_memory_available_is_refused_before_a_shard_is_read(
        copy_of, monkeypatch):
    """Issue 82: a data set's load holds its shards twice (read, then joined); a set that
    cannot fit is refused in one line before any shard is read."""
    folder = copy_of()
    size = sum(f.stat().st_size for f in folder.glob("*.nc"))
    monkeypatch.setattr(dsio, "available_memory", lambda: size)
    monkeypatch.setattr(xr, "open_dataset", lambda *a, **k: pytest.fail("a shard was read"))
    with pytest.raises(dsio.DataSetError, match=r"needs about .* GiB of memory, .* GiB "
                                                r"available; nothing was read$"):
        dsio.load(folder)


def test_measured_and_user_registered_labels_load(tmp_path, small):
    assert dsio.load(small).sizes["sample"] == 20  # a clean generated set
    ds = make_synthetic(gears=(1,), n_variants=1, ops=((2000.0, 7.0),), n_time=64)
    ds["fault"].values[:] = "unknown"  # measured data: state not known
    ds["fault"].values[0] = "worn_bearing"
    folder = tmp_path / "measured"
    write_dataset(ds, folder)
    assert "'worn_bearing'" in load_message(folder)
    m = _manifest(folder)
    m["config"] = {"variants": {"worn_bearing": {"severities": [1.0]}}}  # its own class
    (folder / dsio.MANIFEST).write_text(json.dumps(m))
    assert set(dsio.load(folder)["fault"].values) == {"unknown", "worn_bearing"}
    assert math.isnan(float(dsio.load(folder)["position_deg"].values[0]))  # NaN: no position
