"""Data-set recording: window starts and the bench amplifier (swgsim.sensing.acquisition)."""

import numpy as np
import pytest

from swgcli import dataset_preset
from swgsim.base.typed import check_tree
from swgsim.datasets.config import dataset_config
from swgsim.sensing.acquisition import (
    Amplifier,
    acquire,
    quantise,
    sinc_taps,
    start_angles,
)


def parse_acquisition(cfg):
    """The acquisition option through the data-set door, then its range checks."""
    acq = dataset_config({"acquisition": cfg}).acquisition
    check_tree(acq, "dataset.acquisition")
    return acq

AMP = Amplifier(name="test", noise_uv_rms=2.4, excitation_v=3.3, vref_v=1.2, gain=128.0,
                bits=24, order=3, oversample=4)


def test_bench_preset_cites_its_amplifier():
    acq = parse_acquisition(dataset_preset("bench")["acquisition"])
    a = acq.amplifier
    assert acq.start == "random" and "ADS131M04" in a.name
    # 2.40 uV rms at 3.3 V excitation, +-1.2 V / 128 full scale, 24 bit
    assert a.noise_mvv == pytest.approx(2.4e-3 / 3.3)
    assert a.range_mvv == pytest.approx(1.2 / 128 / 3.3 * 1e3)
    assert a.lsb_mvv == pytest.approx(2 * a.range_mvv / 2**24)
    paper = parse_acquisition(dataset_preset("paper")["acquisition"])
    assert paper.start == "fixed" and paper.amplifier is None


@pytest.mark.parametrize("cfg, key", [
    ({"start": "sometimes"}, "dataset.acquisition.start"),
    ({"begin": "fixed"}, "dataset.acquisition.begin: unknown key"),
    ({"wg_start_deg": float("nan")}, "wg_start_deg"),
    ({"amplifier": 3}, "dataset.acquisition.amplifier: must be a mapping"),
    ({"amplifier": {"name": "x", "noise_uv_rms": 1, "excitation_v": 0, "vref_v": 1,
                    "gain": 1}}, "amplifier.excitation_v must lie in \\(0"),
    ({"amplifier": {"name": "x", "noise_uv_rms": 1, "excitation_v": 1, "vref_v": 1,
                    "gain": 1, "oversample": 2.5}}, "amplifier.oversample"),
    ({"amplifier": {"name": "x", "noise_uv_rms": -1, "excitation_v": 1, "vref_v": 1,
                    "gain": 1}}, "amplifier.noise_uv_rms"),
    ({"amplifier": {"name": "x", "noise": 1}}, "amplifier.noise: unknown key"),
    ({"amplifier": {"name": "x", "noise_uv_rms": 1}}, "amplifier.excitation_v: missing"),
])
def test_bad_acquisition_is_refused_naming_the_key(cfg, key):
    with pytest.raises(ValueError, match=key):
        parse_acquisition(cfg)


def test_start_angles_fixed_and_random():
    rng = np.random.default_rng(0)
    fixed = start_angles(parse_acquisition({"start": "fixed", "wg_start_deg": 30.0}), 5, rng,
                         100.0)
    np.testing.assert_array_equal(fixed, np.deg2rad(30.0))
    phi = start_angles(parse_acquisition({"start": "random"}), 20000, rng, 100.0)
    wg = np.mod(phi, 2 * np.pi) / (2 * np.pi)  # WG angle, in revolutions
    out = np.mod(-phi / 100.0, 2 * np.pi) / (2 * np.pi)  # output angle ≈ -φ_in / N
    for u in (wg, out):  # both uniform over a revolution: every decile holds about 10 %
        frac = np.histogram(u, bins=10, range=(0, 1))[0] / u.size
        assert np.abs(frac - 0.1).max() < 0.01


def test_sinc_taps_response_matches_the_sinc_cubed():
    q = 4
    taps = sinc_taps(q, 3)
    assert taps.size == 3 * (q - 1) + 1 and taps.sum() == pytest.approx(1.0, abs=1e-15)
    f_fine = 40e3
    for f in (333.0, 1700.0, 4100.0, 7900.0):  # in band, near and above Nyquist of 10 kS/s
        w = 2 * np.pi * f / f_fine
        h = abs(np.sum(taps * np.exp(-1j * w * np.arange(taps.size))))
        expect = abs(np.sin(q * w / 2) / (q * np.sin(w / 2))) ** 3
        assert h == pytest.approx(expect, rel=1e-12)


def test_acquire_filters_samples_and_adds_the_stated_noise():
    q, n_t, lead = AMP.oversample, 4000, AMP.lead_samples(10e3)
    fs, f = 10e3, 1234.5
    t = np.arange(q * (n_t + 2 * lead)) / (q * fs)
    x = np.broadcast_to(0.1 * np.sin(2 * np.pi * f * t), (3, 5, t.size)).copy()
    quiet = Amplifier(**{**AMP.__dict__, "noise_uv_rms": 0.0})
    y = acquire(x, quiet, np.random.default_rng(0), lead)
    assert y.shape == (3, 5, n_t)
    # amplitude: the sinc3 response at f; delay: order (q - 1) / 2 fine samples
    w = 2 * np.pi * f / (q * fs)
    gain = abs(np.sin(q * w / 2) / (q * np.sin(w / 2))) ** 3
    tk = (lead + np.arange(n_t)) / fs + (q - 1) / (q * fs) - AMP.group_delay_s(fs)
    np.testing.assert_allclose(y[0, 0], 0.1 * gain * np.sin(2 * np.pi * f * tk),
                               atol=2 * quiet.lsb_mvv)
    noisy = acquire(x, AMP, np.random.default_rng(1), lead)
    sd = (noisy - y).std()  # measured on the signal
    assert sd == pytest.approx(AMP.noise_mvv, rel=0.02)
    assert np.allclose(np.round(noisy / AMP.lsb_mvv) * AMP.lsb_mvv, noisy, atol=1e-12)
    big = acquire(x * 1e3, quiet, np.random.default_rng(0), lead)  # beyond the range: clipped
    assert np.abs(big).max() == pytest.approx(AMP.range_mvv)


def test_acquire_refuses_bad_lengths():
    with pytest.raises(ValueError, match="oversample"):
        acquire(np.zeros((1, 5, 4 * 10 + 1)), AMP, np.random.default_rng(0), 4)
    with pytest.raises(ValueError, match="n_lead"):
        acquire(np.zeros((1, 5, 4 * 40)), AMP, np.random.default_rng(0), 1)


def test_quantise_in_place_is_the_array_form_bit_for_bit():
    """quantise's in-place operations against clip(round((x + noise) / lsb) * lsb), with
    values beyond the range and on half-LSB ties; the input is left as it was."""
    amp = AMP
    rng = np.random.default_rng(3)
    x = rng.normal(0.0, 2.0, (7, 5, 300))
    x[0, 0, :4] = np.array([0.5, 1.5, -2.5, 1e3]) * amp.lsb_mvv  # ties, and beyond range
    noise = rng.normal(0.0, amp.noise_mvv, x.shape)
    before = x.copy()
    for nz in (noise, None):
        want = np.clip(np.round((x if nz is None else x + nz) / amp.lsb_mvv) * amp.lsb_mvv,
                       -amp.range_mvv, amp.range_mvv)
        assert np.array_equal(quantise(x, amp, nz), want)
    assert np.array_equal(x, before)
