"""A small synthetic schema-v1 data set with planted class signatures, for the deep tests.

Not physics: a few lines of trigonometry that look like the paper's Fig. 6 in spirit
(2nd-order ripple of the wave generator, s1 ~ s3 and s2 ~ s4 on a healthy gear, faults as
offsets, amplitude changes, local bumps and efficiency shifts). The three gears differ in
gauge gains, bridge offsets and gauge phase errors, so that leave-one-gear-out is not
trivial without the reference normalisation. Other test files import
:func:`make_toy_dataset` and :func:`write_toy_dataset` from here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swgsim.datasets.schema import MANIFEST, make_dataset, write_shard
from swgsim.files.ownership import atomic_write_json
from swgsim.gear.faults import PAPER_CLASSES as FAULT_CLASSES

SPEEDS_RPM = (2000.0, 4000.0)
TORQUES_NM = (7.0, 70.0)


def _gear_params(gear: int) -> dict:
    rng = np.random.default_rng(1000 + gear)
    return {
        "gain": 1.0 + 0.15 * rng.standard_normal(5),
        "offset": 0.08 * rng.standard_normal(5),
        "phase": np.deg2rad(3.0) * rng.standard_normal(5),
        "amp": 0.3 * (1.0 + 0.1 * (gear - 2)),
        "eta0": 0.74 + 0.02 * (gear - 2),
    }


def _window(rng, gp, fault, variant, n_in, t_out, disturbed, t):
    """One window, shape (5, T) [mV/V], and its efficiency."""
    theta0 = rng.uniform(0, 2 * np.pi)
    theta = theta0 + 2 * np.pi * n_in / 60.0 * t  # (T,) input angle [rad]
    psi = np.deg2rad([0.0, 0.0, 90.0, 180.0, 270.0]) + gp["phase"]  # gauge angles
    sev = 1 + variant % 3
    pos = np.deg2rad(360.0 / 7 * (variant // 3))
    amp = np.full(5, gp["amp"])
    s = np.empty((5, t.size))
    s[0] = 0.004 * t_out + 0.03 * np.cos(2 * theta)
    for i in range(1, 5):
        s[i] = amp[i] * np.cos(2 * (theta - psi[i])) + 0.002 * t_out
    eta = gp["eta0"] + 0.0006 * t_out - 0.00001 * n_in
    if fault == "reduced_damping":
        eta += 0.015 * sev
    elif fault == "reduced_stiffness":
        s[0] += 0.01 * sev * np.cos(4 * theta)
        eta -= 0.004 * sev
    elif fault == "eccentric_wg":
        for i in range(1, 5):
            s[i] += 0.04 * sev * (np.cos(theta - psi[i] - pos) + np.cos(pos - psi[i]))
    elif fault == "root_tooth_crack":
        s[1:] *= 1.0 - 0.06 * sev * (1 + 0.5 * np.cos(2 * theta - pos))
    elif fault == "tip_tooth_crack":
        bump = np.exp(-(np.angle(np.exp(1j * (2 * theta - pos))) ** 2) / 0.05)
        s[1] += 0.05 * sev * bump
        s[3] -= 0.03 * sev * bump
    s += 0.01 * rng.standard_normal(s.shape)
    eta += 0.001 * rng.standard_normal()
    if disturbed:  # paper eq. (10): offset and sub-harmonics of the input speed
        w = 2 * np.pi * n_in / 60.0
        for i in range(5):
            a = rng.uniform(0, 0.04, 5)
            ph = rng.uniform(0, 2 * np.pi, 5)
            s[i] += a[0] + sum(a[j] * np.sin(w / j * t + ph[j]) for j in range(1, 5))
    s = gp["gain"][:, None] * s + gp["offset"][:, None]
    return s, eta


def make_toy_dataset(
    n_variants: int = 6,
    n_time: int = 256,
    gears: tuple[int, ...] = (1, 2, 3),
    disturbed: tuple[bool, ...] = (False, True),
    seed: int = 0,
):
    """Build the toy data set in memory.

    Returns
    -------
    xarray.Dataset
        Schema v1; ``len(gears) * 6 * n_variants * 4 * len(disturbed)`` windows plus one
        reference window per gear, operating point and disturbed flag.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n_time) / 4000.0  # 64 ms at 4 kHz [s]
    sig, meta = [], {k: [] for k in (
        "gear", "fault", "variant", "severity", "position_deg", "n_in_rpm", "t_out_nm",
        "disturbed", "reference", "efficiency", "n_in_mean_rpm", "t_out_mean_nm")}
    for g in gears:
        gp = _gear_params(g)
        for dist in disturbed:
            for n_in in SPEEDS_RPM:
                for t_out in TORQUES_NM:
                    rows = [("healthy", -1, True)] + [
                        (f, v, False) for f in FAULT_CLASSES for v in range(n_variants)]
                    for fault, v, ref in rows:
                        s, eta = _window(rng, gp, fault, max(v, 0), n_in, t_out, dist, t)
                        sig.append(s)
                        meta["gear"].append(g)
                        meta["fault"].append(fault)
                        meta["variant"].append(v)
                        meta["severity"].append(0.0 if fault == "healthy" else 1 + v % 3)
                        meta["position_deg"].append(np.nan)
                        meta["n_in_rpm"].append(n_in)
                        meta["t_out_nm"].append(t_out)
                        meta["disturbed"].append(dist)
                        meta["reference"].append(ref)
                        meta["efficiency"].append(eta)
                        meta["n_in_mean_rpm"].append(n_in)
                        meta["t_out_mean_nm"].append(t_out)
    return make_dataset(np.stack(sig), t, {k: np.asarray(v) for k, v in meta.items()},
                        attrs={"seed": seed, "generator": "tests/learn/test_deep_toy.py"})


def write_toy_dataset(path: str | Path, **kwargs) -> Path:
    """Write :func:`make_toy_dataset` as a one-shard data-set directory; return its path."""
    path = Path(path)
    ds = make_toy_dataset(**kwargs)
    digest = write_shard(ds, path / "shard-000.nc")
    atomic_write_json(path / MANIFEST, {
        "schema_version": 1, "complete": True,
        "shards": {"shard-000.nc": {"sha256": digest}},
    })
    return path


def test_toy_dataset_is_schema_v1(tmp_path):
    from swgsim.datasets.schema import load

    path = write_toy_dataset(tmp_path / "toy", n_variants=3, n_time=64)
    ds = load(path)
    assert ds["strain_signal"].shape == (3 * 2 * 4 * (6 * 3 + 1), 5, 64)
    assert int(ds["reference"].sum()) == 3 * 2 * 4
    assert set(np.unique(ds["fault"].values)) == set(FAULT_CLASSES)
