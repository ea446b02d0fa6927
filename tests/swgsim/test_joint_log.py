"""The joint log reader (swgsim.datasets.joint_log) on a cut of the UR3 CobotOps format,
written here, and on the real day where the workplace holds it beside the repository."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from swgsim.datasets.conditions import TemperatureTrace, trace_table
from swgsim.datasets.joint_log import (
    LOG_COLUMNS,
    read_joint_log,
    write_joint_log,
    write_temperature_table,
)

HEADER = ("Num;Timestamp;Current_J0;Temperature_T0;Current_J1;Temperature_J1;Current_J2;"
          "Temperature_J2;Current_J3;Temperature_J3;Current_J4;Temperature_J4;Current_J5;"
          "Temperature_J5;Speed_J0;Speed_J1;Speed_J2;Speed_J3;Speed_J4;Speed_J5;"
          "Tool_current;cycle ;Robot_ProtectiveStop;grip_lost;;;;")


def _row(num: int, stamp: str, temp: float, stop: str = "False", missing: bool = False) -> str:
    cells = []
    for j in range(6):
        cells += ["" if missing else f"{0.5 * j - 1:.3f}".replace(".", ","),
                  "" if missing else f"{temp + j:.4f}".replace(".", ",")]
    cells += ["" if missing else "0,01"] * 6 + ["" if missing else "0,08", "7",
                                                "" if missing else stop, "True"]
    return f"{num};{stamp};" + ";".join(cells) + ";;;;"


def _cut(path: Path, rows: list[str] | None = None) -> Path:
    """A cut of the format: 3 readings, one row without readings, a 2-h gap, 2 readings."""
    rows = rows or [
        _row(1, "2022-10-26T08:17:21.847Z", 27.875),
        _row(2, "2022-10-26T08:17:22.852Z", 27.9375, stop="True"),
        _row(3, "2022-10-26T08:17:23.857Z", 28.0, missing=True),
        _row(4, "2022-10-26T08:17:24.863Z", 28.0),
        _row(5, "2022-10-26T10:17:24.863Z", 30.5),
        _row(6, "2022-10-26T10:17:25.863Z", 30.5625)]
    path.write_text("\n".join([HEADER, *rows]) + "\n")
    return path


def test_a_cut_of_the_ur3_format_is_mapped(tmp_path):
    log = read_joint_log(_cut(tmp_path / "day.csv"))
    assert log.n == 6 and log.name == "day" and log.start == "2022-10-26T08:17:21.847Z"
    np.testing.assert_allclose(log.t_s[:2], [0.0, 1.005])
    np.testing.assert_array_equal(log.gap_rows, [4])  # the 2-h step
    assert log.temperature_c[0, 0] == 27.875 and log.temperature_c[0, 5] == 32.875
    assert np.isnan(log.temperature_c[2]).all() and np.isnan(log.current_a[2]).all()
    assert log.current_a[0, 3] == pytest.approx(0.5)  # decimal comma
    np.testing.assert_array_equal(log.protective_stop, [0, 1, 0, 0, 0, 0])
    assert log.grip_lost.all() and (log.cycle == 7).all()  # 'cycle ' with its space


@pytest.mark.parametrize(("cell", "column", "match"), [
    ("Current_J3", "abc", r"column 'Current_J3' \(current\[3\]\), row 1 \(line 3\): "
                          r"'abc' is not a number"),
    ("Robot_ProtectiveStop", "maybe", r"column 'Robot_ProtectiveStop' \(protective_stop\), "
                                      r"row 1 \(line 3\): 'maybe' is not a flag"),
    ("Timestamp", "yesterday", r"column 'Timestamp' \(time\), row 1 \(line 3\): 'yesterday' "
                               r"is not a time stamp"),
    # issue 82, cause 3: any finite number was taken (1e30 degC gave an ambient of -1.9e27)
    ("Temperature_J2", "1e30", r"column 'Temperature_J2' \(temperature\[2\]\), row 1 "
                               r"\(line 3\): 1e\+30 degC outside \[-40, 150\] degC: "),
    ("Current_J4", "1e200", r"column 'Current_J4' \(current\[4\]\), row 1 \(line 3\): "
                            r"1e\+200 A outside \[-100, 100\] A: "),
    ("Speed_J1", "-40", r"column 'Speed_J1' \(speed\[1\]\), row 1 \(line 3\): -40 rad/s "
                        r"outside \[-12.5664, 12.5664\] rad/s: "),
    ("Tool_current", "11", r"column 'Tool_current' \(tool_current\), row 1 \(line 3\): 11 A "
                           r"outside \[-10, 10\] A: "),
])
def test_a_malformed_row_is_refused_naming_row_and_column(tmp_path, cell, column, match):
    path = _cut(tmp_path / "day.csv")
    lines = path.read_text().splitlines()
    names = lines[0].split(";")
    cells = lines[2].split(";")
    cells[names.index(cell)] = column
    lines[2] = ";".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=match):
        read_joint_log(path)


def test_a_missing_column_is_refused_naming_it(tmp_path):
    path = _cut(tmp_path / "day.csv")
    path.write_text(path.read_text().replace("Temperature_T0", "Temperature_J0"))
    with pytest.raises(ValueError, match=r"column 'Temperature_T0' \(temperature\[0\]\) is "
                                         r"missing"):
        read_joint_log(path)
    assert "cycle " in LOG_COLUMNS


def test_the_real_day_reads_as_published(ur3_day):
    log = read_joint_log(ur3_day)
    assert log.n == 7409 and log.gap_rows.tolist() == [2869]
    assert (log.t_s[2869] - log.t_s[2868]) / 3600 == pytest.approx(5.226, abs=1e-3)
    assert np.isnan(log.temperature_c).any(axis=1).sum() == 54
    assert (log.cycle.min(), log.cycle.max()) == (1, 264)
    assert log.protective_stop.sum() == 278 and log.grip_lost.sum() == 243


def test_a_written_log_reads_back(tmp_path):
    log = read_joint_log(_cut(tmp_path / "day.csv"))
    write_joint_log(log, tmp_path / "again.csv")
    back = read_joint_log(tmp_path / "again.csv")
    np.testing.assert_allclose(back.t_s, log.t_s, atol=1e-6)
    for name in ("temperature_c", "current_a", "speed_rad_s", "cycle", "protective_stop",
                 "grip_lost", "gap_rows"):
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name))


def test_a_joints_temperature_table_cuts_the_gap_or_keeps_it(tmp_path):
    """Joint 1's readings (the row without one left out) as hour,temperature_c, read back
    as a trace of mode 'hours'; the 2-h gap cut to the log's median step, or kept."""
    log = read_joint_log(_cut(tmp_path / "day.csv"))
    temp = [28.875, 28.9375, 29.0, 31.5, 31.5625]
    for keep, gap_s in ((False, 1.005), (True, 7200.0)):
        path = tmp_path / f"j1_{keep}.csv"
        write_temperature_table(log, 1, path, keep_gaps=keep)
        h, t = trace_table(TemperatureTrace(str(path), mode="hours"), "k")
        np.testing.assert_allclose(h * 3600, [0, 1.005, 3.016, 3.016 + gap_s, 4.016 + gap_s],
                                   atol=0.004)  # written to 1e-6 h
        np.testing.assert_array_equal(t, temp)
    with pytest.raises(ValueError, match=r"^joint must lie in \[0, 5\], got 6$"):
        write_temperature_table(log, 6, tmp_path / "j6.csv")


def test_the_real_shoulders_table_spans_its_operating_hours(tmp_path, ur3_day):
    """docs/DATASET.md: the shoulder's table, the 5.2-h gap cut, 2.09 operating hours."""
    rows = write_temperature_table(read_joint_log(ur3_day), 1, tmp_path / "j1.csv")
    assert rows.shape == (7355, 2) and rows[-1, 0] == pytest.approx(2.087, abs=1e-3)
    assert (rows[:, 1].min(), rows[:, 1].max()) == (29.3125, 40.5)


def test_a_log_longer_than_its_consumers_hold_is_refused_before_it_is_parsed(tmp_path,
                                                                           monkeypatch):
    """Issue 82, cause 2: a log inside the reader's byte and cell bounds needed about 19
    times its size once calibrated (1 M rows: 4.5 GB; 3 M: a MemoryError traceback).
    The reader bounds the rows by what its consumers hold (MAX_LOG_ROWS), counted from the
    file before any cell is parsed: one line. (The bound is lowered here to keep the test
    small.)"""
    from swgsim.datasets import joint_log, recording_table

    monkeypatch.setattr(joint_log, "MAX_LOG_ROWS", 3)

    def parsed(*a, **k):
        raise AssertionError("the table was parsed before its rows were counted")
    monkeypatch.setattr(recording_table, "_read_csv_chunks", parsed)
    path = _cut(tmp_path / "day.csv")
    with pytest.raises(ValueError, match=r"day.csv: 6 rows of 23 mapped columns are 138 "
                                         r"values, more than the 69 read"):
        read_joint_log(path)
