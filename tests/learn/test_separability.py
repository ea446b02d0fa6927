"""Class separability from the healthy windows (learn/studies/separability.py) on the toy set."""

import numpy as np
import pytest
from data_sets import make_toy_dataset

from learn.studies.separability import plot_separability, separations, summary_table


def test_planted_signature_separates_and_a_healthy_twin_does_not(tmp_path):
    ds = make_toy_dataset(n_variants=12, n_time=256, gears=(1,), disturbed=(False,))
    fault = ds["fault"].values.astype(object)
    twin = (fault == "healthy") & ~ds["reference"].values & (ds["variant"].values % 2 == 1)
    fault[twin] = "healthy_twin"  # healthy windows under another name: no signature
    ds["fault"] = ("sample", fault.astype(str))
    sep = separations(ds, disturbed=False, n_harmonics=6)
    assert set(sep) == set(np.unique(fault[~ds["reference"].values]))
    tab = summary_table(sep).set_index("fault")
    # the toy plants an order-4 ripple (stiffness), amplitude modulation (root crack) and
    # an efficiency shift (damping); its eccentricity sits at input order 1, which the
    # harmonic fit takes for the eq. (10) disturbance and drops
    assert tab.loc["reduced_stiffness", "beyond_p95"] > 0.9
    assert tab.loc["root_tooth_crack", "beyond_p95"] > 0.9
    assert tab.loc["reduced_damping", "beyond_p95"] > 0.9
    assert tab.loc["healthy_twin", "beyond_p95"] < 0.35
    assert plot_separability(sep, tmp_path / "sep.png").is_file()


def test_bad_input_is_refused():
    ds = make_toy_dataset(n_variants=3, n_time=64, gears=(1,), disturbed=(False,))
    with pytest.raises(ValueError, match="n_harmonics"):
        separations(ds, n_harmonics=0)
    with pytest.raises(ValueError, match="healthy"):
        summary_table({"eccentric_wg": np.ones(3)})
