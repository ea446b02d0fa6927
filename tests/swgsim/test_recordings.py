"""A user's recording as a stream (swgsim.datasets.recordings): simulated lives written as a
logger's table come back as the stream they were, through CSV and Parquet, bursts or a
continuous recording, raw counts or mV/V, an hours or a wall clock; every bad table and
mapping is refused in one line naming the column and the row, before anything is written.
The monitor on an imported stream: tests/apps/test_import_app.py."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest
import yaml

from swgsim.datasets.recording_mapping import read_mapping, recording_mapping
from swgsim.datasets.recording_table import MIN_WINDOW_SAMPLES, flag, stream_table
from swgsim.datasets.recordings import import_recording
from swgsim.datasets.schema import load, read_manifest
from swgsim.files.ownership import STAMP

#: Variables a stream carries unchanged through the table (bit for bit).
EXACT = ("strain_signal", "gear", "n_in_rpm", "t_out_nm", "hour", "commissioning",
         "reference", "variant")
#: Window means of the table's columns: equal to rounding (a mean of n_t equal values).
MEANS = ("efficiency", "n_in_mean_rpm", "t_out_mean_nm")


@pytest.fixture(scope="module")
def life(tmp_path_factory):
    """Gear 3 of the tiny_life preset written by generate, 2 h: commissioning 1 h, an
    eccentric WG (severity 0.1) from 1.5 h; 120 windows at two operating points."""
    from swgcli import dataset_preset
    from swgsim.datasets.config import dataset_config
    from swgsim.datasets.generate import generate

    cfg = dataset_config(dataset_preset("tiny_life"))
    cfg.gears = [g for g in cfg.gears if g.id == 3]
    cfg.life = dataclasses.replace(cfg.life, hours=2.0, commissioning_h=1.0,
                                   fault=dataclasses.replace(cfg.life.fault, onset_h=1.5))
    out = tmp_path_factory.mktemp("life")
    generate(cfg, out, progress=False)
    return load(out)


@pytest.fixture(scope="module")
def motion_life():
    """The tiny_motion_life preset (a profile: reversing speed, a 24-count Hall sensor on
    the input, a 20-bit output encoder), in memory: 60 windows."""
    from swgcli import dataset_preset
    from swgsim.datasets.config import dataset_config
    from swgsim.datasets.life import LifeSimulator, life_dataset
    from swgsim.datasets.plan import plan

    cfg = dataset_config(dataset_preset("tiny_motion_life"))
    return life_dataset(LifeSimulator(plan(cfg), cfg.gears[0].id, cfg.life))


def _write(df: pd.DataFrame, mapping: dict, tmp_path, name: str = "rec.csv"):
    path = tmp_path / name
    if path.suffix == ".parquet":
        df.to_parquet(path)
    else:
        df.to_csv(path, index=False)
    (tmp_path / "map.yaml").write_text(yaml.safe_dump(mapping))
    return path, tmp_path / "map.yaml"


def _same_stream(orig, got, exact=EXACT) -> None:
    for v in exact:
        np.testing.assert_array_equal(got[v].values, orig[v].values, err_msg=v)
    for v in MEANS:  # sums of equal values: exact to a few units of the last place
        np.testing.assert_allclose(got[v].values, orig[v].values, rtol=1e-13, err_msg=v)
    comm = orig["commissioning"].values
    assert (got["fault"].values[comm] == "healthy").all()
    assert (got["fault"].values[~comm] == "unknown").all()


@pytest.mark.parametrize("name", ["rec.csv", "rec.parquet"])
def test_a_life_written_as_a_table_comes_back_as_its_stream(life, tmp_path, name):
    df, mapping = stream_table(life)
    rec, yml = _write(df, mapping, tmp_path, name)
    s = import_recording(rec, yml, tmp_path / "stream")
    got = load(tmp_path / "stream")  # every check of a data set on load
    _same_stream(life, got)
    n = life.sizes["sample"]
    assert s["windows"] == s["windows_cut"] == s["segments"] == n and s["outside_points"] == 0
    assert s["commissioning_windows"] == {"4000 rpm, 7 N m": 30, "4000 rpm, 70 N m": 30}
    n_t = life.sizes["time"]
    np.testing.assert_array_equal(got["recording_row"].values, np.arange(n) * n_t)
    mf = read_manifest(tmp_path / "stream")
    assert mf["complete"] and mf["config"]["recording"]["rows"] == n * n_t
    stamp = json.loads((tmp_path / "stream" / STAMP).read_text())
    assert stamp["apps"] == ["swgsim-import"] and set(mf["shards"]) <= set(stamp["files"])


def test_csv_and_parquet_give_the_same_content(life, tmp_path):
    df, mapping = stream_table(life)
    hashes = []
    for name in ("rec.csv", "rec.parquet"):
        rec, yml = _write(df, mapping, tmp_path, name)
        hashes.append(import_recording(rec, yml, tmp_path / name.replace(".", "_"))[
            "content_sha256"])
    assert hashes[0] == hashes[1]


def test_angles_and_temperature_carried_through(motion_life, tmp_path):
    """A profile life's angle channels (reversing: the speed's sign) come back bit for
    bit, its input sensor's count in the config the monitor reads; a temperature column
    gives each window's mean as temperature_c [degC]."""
    df, mapping = stream_table(motion_life)
    n_t = motion_life.sizes["time"]
    temp = 20.0 + np.arange(motion_life.sizes["sample"]) * 0.25  # one value per window
    df["joint_temp"] = np.repeat(temp, n_t) + np.tile(np.linspace(-0.1, 0.1, n_t),
                                                      temp.size)
    mapping["temperature"] = "joint_temp"
    rec, yml = _write(df, mapping, tmp_path, "rec.parquet")
    import_recording(rec, yml, tmp_path / "stream")
    got = load(tmp_path / "stream")
    _same_stream(motion_life, got, EXACT + ("phi_in_meas", "phi_out_meas"))
    np.testing.assert_allclose(got["temperature_c"].values, temp, rtol=1e-13)
    assert got["temperature_c"].dtype == np.float64 and got["temperature_c"].dims == (
        "sample",)
    cfg = json.loads(got.attrs["config"])
    assert cfg["profile"]["angles"]["input_counts_per_rev"] == 24


def test_bursts_whose_time_restarts_and_a_wall_clock(life, tmp_path):
    """Each burst's time from 0 and the clock as ISO time stamps: the same windows, at
    the hours since the recording's first row."""
    df, mapping = stream_table(life)
    n_t = life.sizes["time"]
    fs = life.attrs["sample_rate_hz"]
    df["time_s"] = np.tile(np.arange(n_t) / fs, life.sizes["sample"])
    stamps = pd.Timestamp("2025-03-01T06:00:00") + pd.to_timedelta(df["hours"] * 3600,
                                                                    unit="s")
    df["when"] = stamps.dt.strftime("%Y-%m-%dT%H:%M:%S.%f")
    mapping["clock"] = {"column": "when", "unit": "datetime"}
    rec, yml = _write(df.drop(columns="hours"), mapping, tmp_path)
    import_recording(rec, yml, tmp_path / "stream")
    got = load(tmp_path / "stream")
    _same_stream(life, got, ("strain_signal", "n_in_rpm", "t_out_nm", "commissioning"))
    np.testing.assert_allclose(got["hour"].values, life["hour"].values, atol=1e-9)  # 1 µs


def test_raw_counts_through_each_bridges_calibration(life, tmp_path):
    """Counts of a 24-bit converter: each bridge its own gain and offset; the stream holds
    mV/V within half a count of the original."""
    df, mapping = stream_table(life)
    cal = [{"gain_mvv_per_count": 2.0 ** -21 * (1 + 0.1 * i), "offset_counts": 1000.0 * i}
           for i in range(5)]
    for i, c in enumerate(cal):
        df[f"s{i}"] = np.round(df[f"s{i}"].astype(float) / c["gain_mvv_per_count"]
                               + c["offset_counts"]).astype(np.int64)
    mapping["bridges"] = {"unit": "counts", "calibration": cal}
    rec, yml = _write(df, mapping, tmp_path)
    import_recording(rec, yml, tmp_path / "stream")
    got = load(tmp_path / "stream")
    gain = np.array([c["gain_mvv_per_count"] for c in cal])[None, :, None]
    err = np.abs(got["strain_signal"].values.astype(float)
                 - life["strain_signal"].values.astype(float))
    assert (err <= gain / 2 + 1e-7).all()  # half a count, plus float32 rounding (< 1e-7)
    _same_stream(life, got, EXACT[1:])


# ------------------------------------------------------------------ a small logger's table
FS, N_T, RPM, NM = 1000.0, 80, 1500.0, 10.0  # 0.08 s windows: 2 input revolutions


def small(n_bursts: int = 8) -> tuple[pd.DataFrame, dict]:
    """A logger's table: a burst of one window each minute of operation (absolute time,
    hours per burst), a 24-count input sensor and a 20-bit output encoder, and its mapping
    (commissioning: the first 3 bursts)."""
    hours = np.arange(n_bursts) / 60.0
    t = (hours[:, None] * 3600.0 + np.arange(N_T) / FS).ravel()
    psi = 2 * np.pi * RPM / 60.0 * t
    res_in, res_out = 2 * np.pi / 24, 2 * np.pi / 2**20
    df = pd.DataFrame({
        "time_s": t, "hours": np.repeat(hours, N_T),
        **{f"s{i}": 0.2 * np.sin(2 * psi + i) + 0.01 * i for i in range(5)},
        "n_in_rpm": RPM, "t_out_nm": NM + 0.1 * np.sin(psi), "temperature_c": 30.0,
        "p_in_w": 200.0, "p_out_w": 150.0,
        "phi_in": np.floor(psi / res_in) * res_in,
        "phi_out": np.floor(-psi / 100.0 / res_out) * res_out})
    mapping = {"time": "time_s", "clock": {"column": "hours", "unit": "h"},
               "input_angle": {"column": "phi_in", "counts_per_rev": 24},
               "output_angle": {"column": "phi_out", "counts_per_rev": 2**20},
               "temperature": "temperature_c", "power": {"input": "p_in_w", "output": "p_out_w"},
               "operating_points": {"points": [[RPM, NM]]},
               "commissioning_h": 2.5 / 60, "window_s": N_T / FS}
    return df, mapping


def test_the_small_table_imports(tmp_path):
    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    s = import_recording(rec, yml, tmp_path / "stream")
    got = load(tmp_path / "stream")
    assert s["windows"] == 8 and got["commissioning"].values.sum() == 3
    np.testing.assert_allclose(got["efficiency"].values, 0.75, rtol=1e-14)
    assert read_mapping(yml).window_s == N_T / FS


def test_bursts_overlapping_in_clock_hours_refused_naming_the_row(tmp_path):
    """Clock-hour path (issue 43, cause 6): a burst of three windows at 1 min and the next
    burst's clock 0.1 s later, inside the first burst's span (the clock is not operating
    time): refused in one line naming the clock column and the row, not AttributeError."""
    df, mapping = small()
    del mapping["input_angle"], mapping["output_angle"]  # a burst repeated: not its angles
    bursts = [df.iloc[k * N_T:(k + 1) * N_T].copy() for k in range(8)]
    long = pd.concat([bursts[1]] * 3, ignore_index=True)  # three windows at 1/60 h
    long["time_s"] = bursts[1]["time_s"].iloc[0] + np.arange(3 * N_T) / FS
    bursts[2]["hours"] = 1 / 60 + 0.1 / 3600  # 0.1 s after it began: before it ended
    df = pd.concat([bursts[0], long, *bursts[2:]], ignore_index=True)
    rec, yml = _write(df, mapping, tmp_path)
    with pytest.raises(ValueError, match=r"column 'hours' \(clock.column\), row 320 "
                       r"\(line 322\): the window there is at 0.016694 h, not after the "
                       r"one before \(0.016711 h\)") as info:
        import_recording(rec, yml, tmp_path / "stream")
    assert "\n" not in str(info.value) and not (tmp_path / "stream").exists()


def test_a_continuous_recording_cut_one_window_per_interval(tmp_path):
    """30 s without a clock column (the time counts), a stretch at another speed from 10 s
    to 13 s: the windows touching it are left out and counted; one window taken every
    3 s of operation at the first whole window from there."""
    df, mapping = small(1)
    t = np.arange(30_000) / FS
    psi = 2 * np.pi * RPM / 60.0 * t
    df = pd.DataFrame({"time_s": t, **{f"s{i}": 0.2 * np.sin(2 * psi + i) for i in range(5)},
                       "n_in_rpm": np.where((t >= 10) & (t < 13), 2 * RPM, RPM),
                       "t_out_nm": NM})
    mapping = {k: v for k, v in mapping.items() if k in ("time", "operating_points",
                                                          "window_s")}
    mapping.update(commissioning_h=10 / 3600, interval_min=0.05)
    rec, yml = _write(df, mapping, tmp_path, "rec.parquet")
    s = import_recording(rec, yml, tmp_path / "stream")
    got = load(tmp_path / "stream")
    starts = np.arange(30_000 // N_T) * N_T / FS  # every whole window's start [s]
    touch = (starts + N_T / FS > 10) & (starts < 13)
    assert s["outside_points"] == touch.sum() and s["windows_cut"] == starts.size
    want, last = [], -np.inf
    for t0 in starts[~touch]:  # the interval's rule, written out: 3 s less one window
        if t0 >= last + 3.0 - N_T / FS - 1e-9:
            want.append(t0)
            last = t0
    np.testing.assert_allclose(got["hour"].values * 3600, want, atol=1e-9)
    assert s["segments"] == 1 and got["commissioning"].values.sum() == sum(
        w < 10 for w in want)


def test_the_mapping_default_window_is_the_data_sets():
    from swgsim.gear.chain import ChainSettings

    m = recording_mapping({"operating_points": {"points": [[RPM, NM]]},
                           "commissioning_h": 1.0})
    assert m.window_s == ChainSettings().window_s and m.interval_min == 1.0
    assert m.bridges.columns == ["s0", "s1", "s2", "s3", "s4"] and m.clock is None


def test_the_example_mapping_reads():
    """examples/own_joint_mapping.yaml (docs/OWN_JOINT.md) is a mapping the importer takes."""
    from pathlib import Path

    m = read_mapping(Path(__file__).resolve().parents[2] / "examples" /
                     "own_joint_mapping.yaml")
    assert m.bridges.unit == "counts" and len(m.bridges.calibration) == 5
    assert m.input_angle.counts_per_rev == 4096 and m.clock.unit == "h"


def _set(col, row, value):
    def f(df):
        df[col] = df[col].astype(object) if isinstance(value, str) else df[col]
        df.loc[row, col] = value
    return f


def _shift(col, rows, by):
    def f(df):
        df.loc[rows, col] = df.loc[rows, col] + by
    return f


def _scale(col, by):
    def f(df):
        df[col] = df[col] * by
    return f


# (id, change of the table, change of the mapping, message): burst k is rows 80k..80k+79
TABLES = [
    ("missing column", lambda df: df.drop(columns="s3", inplace=True), None,
     r"column 's3' \(bridges.columns\[3\]\) is missing; the table has time_s, hours, s0"),
    ("time not increasing", _set("time_s", 85, 60.0), None,
     r"column 'time_s' \(time\), row 85 \(line 87\): time goes from .* inside a segment"),
    ("gap inside a segment", _shift("time_s", slice(85, 159), 0.5), None,
     r"column 'time_s' \(time\), row 85 \(line 87\): a gap of 0.501 s inside a segment"),
    ("irregular sampling", _shift("time_s", slice(85, 159), 2e-4), None,
     r"row 85 \(line 87\): a step of 0.0012 s; the sample rate 1000 Hz .*irregular"),
    ("clock going back", _set("hours", slice(240, 319), 1 / 60), None,
     r"column 'hours' \(clock.column\), row 240 \(line 242\): the clock goes back"),
    ("not finite", _set("s2", 90, np.nan), None,
     r"column 's2' \(bridges.columns\[2\]\), row 90 \(line 92\): nan is not a finite"),
    ("not a number", _set("s1", 90, "0.1x"), None,
     r"column 's1' \(bridges.columns\[1\]\), row 90 \(line 92\): '0.1x' is not a number"),
    ("bridge beyond 10 mV/V", _set("s4", 90, 12.5), None,
     r"column 's4' \(bridges.columns\[4\]\), row 90 \(line 92\): 12.5 mV/V outside "
     r"\[-10, 10\] mV/V: raw counts"),
    ("speed beyond the catalogue", _set("n_in_rpm", 90, 7000.0), None,
     r"column 'n_in_rpm' \(speed.column\), row 90 \(line 92\): 7000 rpm outside "
     r"\[-6500, 6500\]"),
    ("torque in N mm", _scale("t_out_nm", 1000.0), None,
     r"column 't_out_nm' \(torque\), row 0 \(line 2\): 10000 N m outside .*N mm"),
    ("temperature in kelvin", _scale("temperature_c", 10.0), None,
     r"column 'temperature_c' \(temperature\), row 0 \(line 2\): 300 degC .*kelvin"),
    ("input power in mW", _scale("p_in_w", 1000.0), None,
     r"column 'p_in_w' \(power.input\), row 0 \(line 2\): 200000 W outside "
     r"\[-130010, 130010\] W: .*mW"),
    ("output power beyond the catalogue's", _set("p_out_w", 90, -2e5), None,
     r"column 'p_out_w' \(power.output\), row 90 \(line 92\): -200000 W outside "
     r"\[-130010, 130010\] W"),
    ("angle not monotone while turning", _shift("phi_in", 90, -3 * 2 * np.pi / 24), None,
     r"column 'phi_in' \(input_angle.column\), row 90 \(line 92\): the angle steps by "
     r"-0.5\d+ rad while the speed is 1500 rpm \(not monotone"),
    ("angle in degrees", _scale("phi_in", 180 / np.pi), None,
     r"column 'phi_in' \(input_angle.column\): over row 0 \(line 2\) to row 79 \(line 81\) "
     r"the angle advances .* a unit that cannot be right"),
    ("speed in rad/s", _scale("n_in_rpm", 2 * np.pi / 60), lambda m: m["operating_points"]
     .update(points=[[RPM * 2 * np.pi / 60, NM]]), r"column 'phi_in'.* integrates to "),
    ("output angle of the wrong sign", _scale("phi_out", -1.0), None,
     r"column 'phi_out' \(output_angle.column\): over the segment from row 0 \(line 2\) the "
     r"output angle advances .* sign convention"),
    ("rate too low for the window", None, lambda m: m.update(window_s=0.05),
     rf"column 'time_s' \(time\): sample rate 1000 Hz too low for windows of 0.05 s: 50 "
     rf"samples per window, at least {MIN_WINDOW_SAMPLES}"),
    ("declared rate contradicted", None, lambda m: m.update(sample_rate_hz=2000.0),
     r"the median step is 0.001 s \(1000 Hz\); sample_rate_hz=2000 Hz"),
    ("no window at a declared point", None,
     lambda m: m["operating_points"].update(points=[[3000.0, NM]]),
     r"operating_points: no window is at a declared point .* speeds span \[1500, 1500\]"),
    ("commissioning covers everything", None, lambda m: m.update(commissioning_h=1.0),
     r"commissioning_h=1: it covers every window"),
    ("a point unseen at commissioning", _set("t_out_nm", slice(400, 639), 20.0),
     lambda m: m["operating_points"].update(points=[[RPM, NM], [RPM, 20.0]]),
     r"no commissioning window at operating_points.points\[1\] \[1500.0, 20.0\]"),
]


@pytest.mark.parametrize("change, mchange, match", [t[1:] for t in TABLES],
                         ids=[t[0] for t in TABLES])
def test_bad_tables_refused_in_one_line_before_anything_is_written(tmp_path, change,
                                                                   mchange, match):
    df, mapping = small()
    if change is not None:
        change(df)
    if mchange is not None:
        mchange(mapping)
    rec, yml = _write(df, mapping, tmp_path)
    with pytest.raises(ValueError, match=match) as info:
        import_recording(rec, yml, tmp_path / "stream")
    assert "\n" not in str(info.value)
    assert not (tmp_path / "stream").exists()


MAPPINGS = [
    ("unknown key", lambda m: m.update(bridge={"unit": "mV/V"}),
     r"map.yaml: bridge: unknown key; allowed: operating_points, commissioning_h, time"),
    ("unknown nested key", lambda m: m.update(bridges={"unitt": "counts"}),
     r"map.yaml: bridges.unitt: unknown key; allowed: columns, unit, calibration"),
    ("unknown unit", lambda m: m.update(speed={"column": "n_in_rpm", "unit": "rpm/s"}),
     r"speed.unit: must be one of rpm, rad/s, got 'rpm/s'"),
    ("counts without a calibration", lambda m: m.update(bridges={"unit": "counts"}),
     r"bridges.calibration: 0 entries; with unit counts one"),
    ("overlapping points", lambda m: m["operating_points"].update(
        points=[[RPM, NM], [RPM + 150, NM]]), r"operating_points.points\[1\]: .* lies within"),
    ("output angle alone", lambda m: m.pop("input_angle"), r"output_angle: needs input_angle"),
    ("a column mapped twice", lambda m: m.update(torque="n_in_rpm"),
     r"torque: column 'n_in_rpm' is mapped twice \(also speed.column\)"),
    ("counts per revolution of 0", lambda m: m["input_angle"].update(counts_per_rev=0),
     r"input_angle.counts_per_rev must lie in "),
    ("missing commissioning", lambda m: m.pop("commissioning_h"), r"commissioning_h: missing"),
    ("a NaN", lambda m: m.update(commissioning_h=float("nan")),
     r"commissioning_h must be a finite number"),
]


@pytest.mark.parametrize("mchange, match", [t[1:] for t in MAPPINGS],
                         ids=[t[0] for t in MAPPINGS])
def test_bad_mappings_refused_naming_the_key(tmp_path, mchange, match):
    df, mapping = small()
    mchange(mapping)
    rec, yml = _write(df, mapping, tmp_path)
    with pytest.raises(ValueError, match=match):
        import_recording(rec, yml, tmp_path / "stream")
    assert not (tmp_path / "stream").exists()


@pytest.mark.parametrize("name, content, match", [
    ("rec.csv", b"", r"recording .*rec.csv: the file is empty \(0 bytes\)"),
    ("rec.csv", None, r"the table has a header but no data row"),
    ("rec.csv", b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe binary", r"not a CSV table"),
    ("rec.parquet", b"PAR1 this is not parquet", r"not a Parquet table"),
    ("rec.xlsx", b"time_s,s0\n0,0\n", r"suffix '.xlsx'; a table is read from .csv"),
])
def test_files_that_are_not_tables_refused(tmp_path, name, content, match):
    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    path = tmp_path / name
    path.write_bytes(content if content is not None else
                     (",".join(df.columns) + "\n").encode())
    with pytest.raises(ValueError, match=match):
        import_recording(path, yml, tmp_path / "stream")
    assert not (tmp_path / "stream").exists()


def test_reads_are_bounded_and_of_regular_files(tmp_path):
    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    with pytest.raises(ValueError, match=r"0.1 MiB, more than the 0.001\d* MiB read"):
        import_recording(rec, yml, tmp_path / "stream", max_bytes=1049)
    with pytest.raises(ValueError, match=r"recording .*: is a folder; give a file"):
        import_recording(tmp_path, yml, tmp_path / "stream")
    sparse = tmp_path / "holes.csv"  # the guard every input file has (files/inputs.py)
    with open(sparse, "wb") as f:
        f.truncate(64 << 20)
    with pytest.raises(ValueError, match=r"recording .*holes.csv: a sparse file"):
        import_recording(sparse, yml, tmp_path / "stream")
    with pytest.raises(FileNotFoundError):
        import_recording(tmp_path / "none.csv", yml, tmp_path / "stream")
    (tmp_path / "bad.yaml").write_text("operating_points: [")
    with pytest.raises(ValueError, match=r"mapping .*bad.yaml: not YAML"):
        import_recording(rec, tmp_path / "bad.yaml", tmp_path / "stream")
    assert not (tmp_path / "stream").exists()


def test_out_dir_foreign_file_refused_and_our_stream_replaced_only_with_overwrite(tmp_path):
    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    (tmp_path / "theirs").mkdir()
    (tmp_path / "theirs" / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match=r"holds notes.txt, which this project cannot show"):
        import_recording(rec, yml, tmp_path / "theirs")
    assert [p.name for p in (tmp_path / "theirs").iterdir()] == ["notes.txt"]
    first = import_recording(rec, yml, tmp_path / "stream")
    with pytest.raises(ValueError, match=r"pass overwrite=true"):
        import_recording(rec, yml, tmp_path / "stream")
    mapping["commissioning_h"] = 4.5 / 60
    rec, yml = _write(df, mapping, tmp_path)
    second = import_recording(rec, yml, tmp_path / "stream", overwrite=True)
    assert second["content_sha256"] != first["content_sha256"]
    assert load(tmp_path / "stream")["commissioning"].values.sum() == 5


@pytest.mark.parametrize("name", ["rec.parquet", "rec.csv"])
def test_a_table_is_bounded_by_its_cells_before_it_is_parsed(tmp_path, monkeypatch, name):
    """Issue 43, cause 7b: a Parquet file compresses a long constant table to almost
    nothing (50 MiB ran out of 4 GB): rows times mapped columns, from the Parquet metadata
    or the CSV's line count, are checked against the cell limit before anything is parsed."""
    import swgsim.datasets.recording_table as rt

    df, mapping = small()
    df = pd.concat([df] * 40, ignore_index=True)  # 25 600 rows of 14 mapped columns
    rec, yml = _write(df, mapping, tmp_path, name)
    monkeypatch.setattr(rt, "MAX_TABLE_CELLS", 100_000)

    def no_parse(*a, **k):
        raise AssertionError("parsed before the cell limit was checked")
    monkeypatch.setattr(pd, "read_parquet", no_parse)
    monkeypatch.setattr(pd, "read_csv", lambda *a, nrows=None, **k: (
        pd.DataFrame(columns=df.columns) if nrows == 0 else no_parse()))
    with pytest.raises(ValueError, match=r"rec\.\w+: 25600 rows of 14 mapped columns are "
                       r"358400 values, more than the 100000 read") as info:
        import_recording(rec, yml, tmp_path / "stream")
    assert "\n" not in str(info.value) and not (tmp_path / "stream").exists()


def test_a_large_max_bytes_asks_no_more_memory_than_the_file(tmp_path):
    """Issue 82: the table was read with ``read(max_bytes + 1)``, which asks for that much
    memory at once: a MemoryError for a table of kilobytes once ``max_bytes`` passed the
    machine's memory. The buffer is the file's size now."""
    import tracemalloc

    import swgsim.datasets.recording_table as rt

    df, mapping = small()
    rec, _ = _write(df, mapping, tmp_path)
    tracemalloc.start()
    try:
        got, fmt, _ = rt.read_table(rec, {"time_s": "time"}, max_bytes=1 << 40)  # 1 TiB
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert fmt == "csv" and len(got) == len(df)
    assert peak < 64 * rec.stat().st_size + (16 << 20), peak


def test_a_recording_growing_while_it_is_read_is_refused(tmp_path, monkeypatch):
    """A logger writing on between the file's size taken and its read: refused in one
    line, as one grown past max_bytes is (the buffer is the size taken)."""
    import builtins

    import swgsim.datasets.recording_table as rt

    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    size = rec.stat().st_size

    class Growing:  # the file as _read_bytes opens it; a row appended as it is read
        def __init__(self, f):
            self.f = f

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

        def fileno(self):
            return self.f.fileno()

        def read(self, n):
            with builtins.open(rec, "ab") as g:
                g.write(b"1,2,3\n")
            return self.f.read(n)

    monkeypatch.setattr(rt, "open", lambda p, mode: Growing(builtins.open(p, mode)),
                        raising=False)
    with pytest.raises(ValueError, match=rf"rec\.csv: grew while it was read \(past the "
                                         rf"{size} bytes it had\); import a finished file"):
        import_recording(rec, yml, tmp_path / "stream")
    assert not (tmp_path / "stream").exists()


def test_the_recording_is_hashed_from_the_bytes_parsed(tmp_path, monkeypatch):
    """Issue 43, cause 8: a recording appended to, then replaced, right after it was read:
    the stream records the SHA-256 of the bytes it was made of, not of the file found later."""
    import hashlib

    import swgsim.datasets.recording_table as rt

    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    before = rec.read_bytes()
    read = rt._read_bytes

    def then_changed(p, max_bytes):
        data = read(p, max_bytes)
        with open(p, "ab") as f:
            f.write(b"1,2,3\n")  # appended to ...
        (tmp_path / "new.csv").write_bytes(data[: len(data) // 2])
        (tmp_path / "new.csv").replace(p)  # ... then replaced
        return data
    monkeypatch.setattr(rt, "_read_bytes", then_changed)
    import_recording(rec, yml, tmp_path / "stream")
    cfg = json.loads(load(tmp_path / "stream").attrs["config"])
    assert cfg["recording"]["sha256"] == hashlib.sha256(before).hexdigest()
    assert cfg["recording"]["sha256"] != hashlib.sha256(rec.read_bytes()).hexdigest()


@pytest.mark.parametrize("overwrite", [False, True])
def test_two_imports_into_one_folder_one_wins_the_other_is_refused(tmp_path, monkeypatch,
                                                                   overwrite):
    """Issue 43, cause 4: the slow import surveys out_dir, then, during its long read, a
    fast one imports into the same folder and finishes; the slow one is refused in one line
    when it comes to write (the folder checked again under its claim), and the fast one's
    stream is left as it was, with or without overwrite=true."""
    from swgsim.datasets import recordings

    df, mapping = small()
    rec, yml = _write(df, mapping, tmp_path)
    other = dict(mapping, commissioning_h=4.5 / 60)  # another stream
    (tmp_path / "other.yaml").write_text(yaml.safe_dump(other))
    out = tmp_path / "stream"
    if overwrite:
        import_recording(rec, yml, out)  # a stream of this project there already
    read = recordings.recording_stream
    won = {}

    def slow_read(*a, **k):
        monkeypatch.setattr(recordings, "recording_stream", read)
        won["summary"] = import_recording(rec, tmp_path / "other.yaml", out,
                                          overwrite=overwrite)  # the fast one, meanwhile
        won["files"] = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()
                        and not p.name.startswith(".swg-owner")}
        return read(*a, **k)
    monkeypatch.setattr(recordings, "recording_stream", slow_read)
    with pytest.raises(ValueError, match=rf"^out_dir {out}: \S+ (and \d more file\(s\) )?"
                       r"written there by another run since this import checked the "
                       r"folder; nothing was replaced") as info:
        import_recording(rec, yml, out, overwrite=overwrite)
    assert "\n" not in str(info.value)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()
            and not p.name.startswith(".swg-owner")} == won["files"]
    assert load(out)["commissioning"].values.sum() == 5  # the fast one's stream
    assert read_manifest(out)["content_sha256"] == won["summary"]["content_sha256"]


def _continuous(seconds: int = 30) -> tuple[pd.DataFrame, dict]:
    """A continuous recording at the one operating point, no clock column (the time counts),
    every window taken, commissioning its first 10 s; a protective stop flag, all false."""
    t = np.arange(seconds * int(FS)) / FS
    psi = 2 * np.pi * RPM / 60.0 * t
    df = pd.DataFrame({"time_s": t, **{f"s{i}": 0.2 * np.sin(2 * psi + i) for i in range(5)},
                       "n_in_rpm": RPM, "t_out_nm": NM + 0.1 * np.sin(psi),
                       "protective_stop": False})
    mapping = {"time": "time_s", "operating_points": {"points": [[RPM, NM]]},
               "commissioning_h": 10 / 3600, "window_s": N_T / FS, "interval_min": 0.0,
               "stops": ["protective_stop"]}
    return df, mapping


def test_windows_in_a_stop_are_left_out_and_the_rest_is_the_recording_without_it(tmp_path):
    """Two protective stops on whole windows, one inside commissioning (windows 20-22) and one
    after it (200-204), the signals left as they were (only the flag says the joint stands):
    the stream is the one of the table without the stop's rows, window for window (the
    hours to rounding), but for the table rows it names; commissioning is shorter by its
    stop's windows."""
    df, mapping = _continuous()
    stops = [(20, 23), (200, 205)]  # windows [first, end)
    rows = np.concatenate([np.arange(a * N_T, b * N_T) for a, b in stops])
    df.loc[rows, "protective_stop"] = True
    (tmp_path / "flag").mkdir()
    (tmp_path / "cut").mkdir()
    s = import_recording(*_write(df, mapping, tmp_path / "flag", "rec.parquet"),
                         tmp_path / "flag" / "stream")
    cut = df.drop(index=rows).reset_index(drop=True)
    ref = import_recording(*_write(cut, mapping, tmp_path / "cut", "rec.parquet"),
                           tmp_path / "cut" / "stream")
    got, want = load(tmp_path / "flag" / "stream"), load(tmp_path / "cut" / "stream")
    n_stop = sum(b - a for a, b in stops)
    assert s["stopped_windows"] == n_stop and s["outside_points"] == 0
    assert s["windows"] == s["windows_cut"] - n_stop == ref["windows"]
    # the hours to rounding: the cut table's are summed from its later segments' first rows
    _same_stream(want, got, tuple(v for v in EXACT if v != "hour") + ("fault",))
    np.testing.assert_allclose(got["hour"].values, want["hour"].values, rtol=1e-15, atol=0)
    kept = np.delete(np.arange(len(df)), rows)  # the cut table's rows in the recording
    np.testing.assert_array_equal(got["recording_row"].values,
                                  kept[want["recording_row"].values])
    first = got["recording_row"].values // N_T  # the windows taken, by their index
    assert not np.isin(first, np.concatenate([np.arange(a, b) for a, b in stops])).any()
    assert got["commissioning"].values.sum() == 10 * FS // N_T - (stops[0][1] - stops[0][0])


def test_one_flagged_row_leaves_its_window_out(tmp_path):
    df, mapping = _continuous(3)
    df.loc[7 * N_T + 5, "protective_stop"] = True
    mapping["commissioning_h"] = 1 / 3600
    s = import_recording(*_write(df, mapping, tmp_path), tmp_path / "stream")
    got = load(tmp_path / "stream")
    assert s["stopped_windows"] == 1
    np.testing.assert_array_equal(got["recording_row"].values // N_T,
                                  np.delete(np.arange(3 * int(FS) // N_T), 7))


@pytest.mark.parametrize("cells, want", [
    ([True, False], [True, False]), (["True", " false", "1", "0", "TRUE"],
                                     [True, False, True, False, True]),
    ([0.0, 2.0, -1.0], [False, True, True]),
])
def test_a_flag_column_reads_booleans_their_text_or_numbers(cells, want):
    assert flag(pd.DataFrame({"stop": cells}), "stop", "stops[0]", "csv").tolist() == want


@pytest.mark.parametrize("cells, bad", [(["True", "maybe"], "'maybe'"), ([1.0, np.nan], "nan"),
                                        (["True", None], "an empty cell")])
def test_a_cell_that_is_no_flag_is_refused_naming_the_row(cells, bad):
    with pytest.raises(ValueError, match=rf"^column 'stop' \(stops\[0\]\), row 1 \(line 3\): "
                                         rf"{bad} is not a flag \(true/false or a number\)$"):
        flag(pd.DataFrame({"stop": cells}), "stop", "stops[0]", "csv")


def test_no_stops_keeps_an_imported_streams_config_and_a_stop_enters_it(tmp_path):
    df, mapping = _continuous(3)
    mapping["commissioning_h"] = 1 / 3600
    plain = {k: v for k, v in mapping.items() if k != "stops"}
    for name, m in (("none", plain), ("stops", mapping)):
        (tmp_path / name).mkdir()
        import_recording(*_write(df, m, tmp_path / name), tmp_path / name / "stream")
    none, stops = (read_manifest(tmp_path / n / "stream") for n in ("none", "stops"))
    assert "stops" not in none["config"]["mapping"]
    assert stops["config"]["mapping"]["stops"] == ["protective_stop"]
    assert none["config_hash"] != stops["config_hash"]
