"""The extension point: a fault class registered from outside the package (its physics and
its name, nothing edited inside swgsim) is simulated into a data set, in worker processes
too, and the learners list it (docs/ARCHITECTURE.md, "To add a fault")."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swgsim.datasets import schema as dsio
from swgsim.datasets.generate import generate
from swgsim.gear.faults import FAULTS, Fault, display_name, fault_classes, register_fault

NAME = "worn_wg_bearing"


def worn_bearing(params, severity, position_deg):
    """A worn wave-generator bearing: its no-load drag b0 grows by (1 + severity)."""
    gear = dataclasses.replace(params.gear, b0_nm=params.gear.b0_nm * (1.0 + severity))
    return dataclasses.replace(params, gear=gear)


@pytest.fixture
def registered():
    fault = register_fault(Fault(NAME, "I/O dynamics", (0.0, 3.0), False, worn_bearing,
                                 "efficiency drops", display="worn WG bearing"))
    yield fault
    FAULTS.pop(NAME)


def tiny_cfg() -> dict:
    return {
        "name": "ext", "seed": 3,
        "gears": [{"id": 1, "tolerance_seed": 101}, {"id": 2, "tolerance_seed": 102}],
        "variants": {"healthy": {"severities": [0.0]}, NAME: {"severities": [1.0, 2.0]}},
        "operating_points": {"n_in_rpm": [2000.0], "t_out_nm": [39.0]},
        "chain": {"window_s": 0.02, "settle_s": 0.02},
        "disturbance": {"harmonic_mvv": 0.0},
    }


def test_registered_fault_is_simulated_in_worker_processes(registered, tmp_path):
    s = generate(tiny_cfg(), tmp_path / "ds", n_jobs=2, progress=False)
    assert s["complete"] and len(s["computed"]) == 2  # one shard per gear, two workers
    ds = dsio.load(tmp_path / "ds")
    clean = ~ds.disturbed.values & ~ds.reference.values
    fault = ds.fault.values
    assert set(fault[clean]) == {"healthy", NAME}
    for g in (1, 2):
        eta = ds.efficiency.values[clean & (ds.gear.values == g)]
        f = fault[clean & (ds.gear.values == g)]
        sev = ds.severity.values[clean & (ds.gear.values == g)]
        healthy, mild, bad = eta[f == "healthy"][0], eta[sev == 1.0][0], eta[sev == 2.0][0]
        assert healthy > mild > bad  # more drag, less efficiency, in order of severity
    assert fault_classes()[-1] == NAME and display_name(NAME) == "worn WG bearing"


def test_learners_order_a_registered_class_after_the_paper_classes(registered):
    from learn.studies.protocols import class_labels

    y = np.array([NAME, "healthy", "tip_tooth_crack", NAME])
    assert class_labels(y) == ["healthy", "tip_tooth_crack", NAME]


def test_registry_refuses_a_taken_name_and_a_range_without_zero(registered):
    with pytest.raises(ValueError, match="registered already"):
        register_fault(Fault(NAME, "-", (0.0, 1.0), False, worn_bearing, ""))
    with pytest.raises(ValueError, match="must hold 0"):
        register_fault(Fault("other", "-", (0.1, 1.0), False, worn_bearing, ""))
    with pytest.raises(ValueError, match="lower-case identifier"):
        register_fault(Fault("Bad Name", "-", (0.0, 1.0), False, worn_bearing, ""))
