"""The memory a data set needs, estimated per shard and per worker and checked before any
work as disk space is; a data set or life too large is refused naming its keys."""

from __future__ import annotations

import math

import pytest
from bad_input import small_cfg

from swgcli import dataset_preset
from swgsim.datasets import generate as gen
from swgsim.datasets.config import gear_params
from swgsim.datasets.plan import plan
from swgsim.datasets.resources import (
    BYTES_PER_FINE_SAMPLE,
    SHARD_FIXED_BYTES,
    check_memory,
    life_records,
    shard_memory,
)


def test_memory_estimate_scales_with_the_fine_samples_of_a_shard():
    p = plan(small_cfg())
    s = max(p.shards, key=lambda x: x.n_windows)
    ch, amp = p.config.chain, p.config.acquisition.amplifier
    q = 1 if amp is None else amp.oversample
    n_t = round(ch.window_s * ch.sample_rate_hz)
    assert shard_memory(p, s) == SHARD_FIXED_BYTES + BYTES_PER_FINE_SAMPLE * s.n_windows * n_t * q
    p2 = plan(small_cfg(sample_rate_hz=2 * ch.sample_rate_hz))
    assert shard_memory(p2, max(p2.shards, key=lambda x: x.n_windows)) - SHARD_FIXED_BYTES == (
        pytest.approx(2 * (shard_memory(p, s) - SHARD_FIXED_BYTES), rel=1e-3))


def test_a_lifes_memory_grows_with_its_windows_and_records():
    """tiny_life: a record per duty point, healthy and faulty (a step onset), each one
    wave-generator revolution at the slowest input speed plus a window; a life four times
    as long needs more; a payload change doubles the records."""
    cfg = dataset_preset("tiny_life")
    p = plan(cfg)
    n_rec, n_samples = life_records(p)
    ops, ch = p.config.operating_points, p.config.chain
    assert n_rec == len(ops.n_in_rpm) * len(ops.t_out_nm) * 2
    ratio = gear_params(p.config, p.config.gears[0]).gear.ratio
    n_t = round(ch.window_s * ch.sample_rate_hz)
    assert n_samples == math.ceil(ratio * 60 / min(ops.n_in_rpm) * ch.sample_rate_hz) + n_t
    cfg["life"]["hours"] = 32.0
    longer = plan(cfg)
    assert shard_memory(longer, longer.shards[0]) > shard_memory(p, p.shards[0])
    cfg["life"]["conditions"] = {"payload": [[10.0, 1.5]]}
    assert life_records(plan(cfg))[0] == 2 * n_rec


def test_memory_is_checked_per_worker_naming_the_keys():
    p = plan(small_cfg())
    one = max(shard_memory(p, s) for s in p.shards)
    check_memory(p, list(p.shards), 1, available=one + (1 << 30))
    with pytest.raises(ValueError) as e:
        check_memory(p, list(p.shards), 2, available=one + (1 << 30))
    msg = str(e.value)
    assert "\n" not in msg and "2 worker(s)" in msg
    for key in ("dataset.chain.sample_rate_hz", "dataset.chain.window_s", "n_jobs"):
        assert key in msg


def test_a_data_set_too_large_for_memory_is_refused_before_any_work(tmp_path, monkeypatch):
    """1 MHz and 10 s windows (12 GiB per shard): every range holds and the disk check
    passes; on a machine with 8 GiB available it is refused before the folder is made."""
    import swgsim.datasets.resources as res

    monkeypatch.setattr(res, "available_memory", lambda: 8 << 30)
    monkeypatch.setattr(gen, "check_disk_space", lambda *a: None)
    out = tmp_path / "big"
    with pytest.raises(ValueError, match="not enough memory: dataset.chain.sample_rate_hz"):
        gen.generate(small_cfg(sample_rate_hz=1e6, window_s=10.0, settle_s=0.02), out)
    assert not out.exists()


def test_a_life_too_long_for_memory_is_refused_naming_its_hours(tmp_path, monkeypatch):
    """tiny_life over 2,000 h (120,000 windows, about 5 GiB of signals): refused on a
    machine with 4 GiB available, naming dataset.life.hours, before the folder is made."""
    import swgsim.datasets.resources as res

    monkeypatch.setattr(res, "available_memory", lambda: 4 << 30)
    monkeypatch.setattr(gen, "check_disk_space", lambda *a: None)
    cfg = dataset_preset("tiny_life")
    cfg["life"]["hours"] = 2000.0
    out = tmp_path / "long"
    with pytest.raises(ValueError, match=r"not enough memory: .* dataset\.life\.hours=2000 h"):
        gen.generate(cfg, out)
    assert not out.exists()
