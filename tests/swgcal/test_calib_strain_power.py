"""Power of the strain-side acceptance rule on planted bench data (1 % noise).

A 1.5° misplacement of one gauge must be found (accepted, recovered within 20 %) in at
least 9 of 10 seeds and clean data must be left alone in at least 9 of 10 seeds
(``scripts/strain_power.py`` prints the table). Each seed draws its own WG start angles
and noise. Both tests are slow (-m slow): 2 seeds (about 10 s) and the full study (10
seeds, two channels, 180 s: found 10/10, clean 10/10); the default run holds one seed of
each claim in tests/swgcal/test_calib_strain.py.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from strain_power import format_power_table, power_study  # noqa: E402  (a study, in scripts/)


def _check(rows, n_seeds, min_found, min_clean):
    table = format_power_table(rows)
    for r in rows:
        assert r.n_seeds == n_seeds
        assert r.found >= min_found, table + "\n" + str(r.details)
        assert r.clean_left_alone >= min_clean, table + "\n" + str(r.clean_added)
        # the median estimate is the true relative angle within 10 %
        assert r.median_estimate == pytest.approx(r.true_value, rel=0.1), table


@pytest.mark.slow  # held in the default run, per seed, by tests/swgcal/test_calib_strain.py:
# a 1.5 deg misplacement of s2 accepted and recovered within 10 %
# (test_gauge_angle_without_alignment_weight_is_not_estimated_nor_handed_on, 2 s) and
# clean data left alone (test_clean_data_get_no_effect, 1 s); the power over seeds is this
# file's ten-seed study (10 s here for two seeds)
def test_misplacement_power_two_seeds():
    rows = power_study(["gauge_misplacement_s2"], seeds=range(2))
    _check(rows, 2, 2, 2)


@pytest.mark.slow
def test_misplacement_power_ten_seeds():
    rows = power_study(["gauge_misplacement_s2", "gauge_misplacement_s1"], seeds=range(10))
    _check(rows, 10, 9, 9)
