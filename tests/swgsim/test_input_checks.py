"""Bad input refused before work, naming its true cause: the memory a data set needs
(checked as disk space is) and the gauge layout's own keys (not blamed on the mesh)."""

from __future__ import annotations

import pytest
from bad_input import small_cfg

from swgsim.datasets import generate as gen
from swgsim.datasets.plan import plan
from swgsim.datasets.resources import BYTES_PER_FINE_SAMPLE, check_memory, shard_memory


def test_memory_estimate_scales_with_the_fine_samples_of_a_shard():
    p = plan(small_cfg())
    s = max(p.shards, key=lambda x: x.n_windows)
    ch, amp = p.config.chain, p.config.acquisition.amplifier
    q = 1 if amp is None else amp.oversample
    n_t = round(ch.window_s * ch.sample_rate_hz)
    assert shard_memory(p, s) == BYTES_PER_FINE_SAMPLE * s.n_windows * n_t * q
    p2 = plan(small_cfg(sample_rate_hz=2 * ch.sample_rate_hz))
    assert shard_memory(p2, max(p2.shards, key=lambda x: x.n_windows)) == pytest.approx(
        2 * shard_memory(p, s), rel=1e-3)


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


@pytest.mark.parametrize("key, value", [("grid_length_mm", 0.0), ("gauge_factor", -2.0),
                                        ("r_pairs_mm", 50.0), ("r_torque_mm", 0.0)])
def test_gauge_layout_keys_are_blamed_not_the_mesh(key, value):
    cfg = small_cfg()
    cfg["sensors"] = {**cfg.get("sensors", {}), key: value}
    with pytest.raises(ValueError, match=rf"^dataset\.sensors\.{key} must lie in"):
        plan(cfg)
