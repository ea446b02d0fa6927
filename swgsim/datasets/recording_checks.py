"""A recording's time and angle columns checked: its segments, their sampling, and the
angles against the speed and the ratio (:mod:`swgsim.datasets.recordings` calls these with
the mapping's fields; the table itself: :mod:`swgsim.datasets.recording_table`). Every
refusal is one ``ValueError`` line naming the file, the column (with the mapping key it
was given as) and the row.

**Segments** (a logger's bursts; where one begins: docs/DATASET.md, "Imported
recordings"). Inside a segment a time step longer than the sample period (within the
tolerance) is refused as a gap: a clock that does not jump there says the logger did not
stop. The time column may restart at a segment's first row (time since the burst's start).
"""

from __future__ import annotations

import numpy as np

from swgsim.datasets.recording_table import MIN_WINDOW_SAMPLES, row_name

__all__ = ["ANGLE_AGREEMENT", "TURNING_RPM", "check_angle_speed", "check_angle_turns",
           "check_output_angle", "check_sampling", "segment_starts", "unwrap_segments"]

#: Speed above which the joint turns [rpm]: where the angle must move with the speed.
TURNING_RPM = 10.0
#: Relative agreement asked of an angle's advance over a segment with the integrated speed
#: (input angle) or with the input angle over the ratio (output angle), plus two counts:
#: a unit error (rpm for rad/s: 9.5; degrees for rad: 57) or a wrong count per revolution
#: (by a factor 2 or more) is far outside it; the output's elastic twist changes by a few
#: arcmin per load step, under 1 % of one input revolution's output angle [choice].
ANGLE_AGREEMENT = 0.10


def segment_starts(time_s: np.ndarray, clock_s: np.ndarray | None, window_s: float,
                   names: tuple[str, str], fmt: str) -> np.ndarray:
    """First rows of the recording's segments (module docstring).

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        Time column [s].
    clock_s : ndarray, shape (n,), or None
        The clock [s] (operating hours or wall-clock time); None: the time column.
    window_s : float
        Window length [s]: a larger advance of the clock starts a segment.
    names : (str, str)
        The time and clock columns as messages name them.
    fmt : str

    Returns
    -------
    ndarray of int, shape (n_segments,)
        Starting with 0, increasing.

    Raises
    ------
    ValueError
        The clock (or, without one, the time) going back, naming the row.
    """
    clock = time_s if clock_s is None else clock_s
    d = np.diff(clock)
    back = np.flatnonzero(d < 0)
    if back.size:
        i = int(back[0]) + 1
        what = ("time goes back" if clock_s is None else "the clock goes back")
        raise ValueError(f"{names[0] if clock_s is None else names[1]}, {row_name(i, fmt)}: "
                         f"{what} from {clock[i - 1]:.9g} to {clock[i]:.9g} s"
                         f"{'' if clock_s is None else ' (since the first row)'}; rows must be in "
                         "recording order" + (" (without a clock column the time column is "
                                              "the clock)" if clock_s is None else ""))
    return np.concatenate([[0], np.flatnonzero(d > window_s) + 1]).astype(np.int64)


def _inside(n: int, starts: np.ndarray) -> np.ndarray:
    """Whether step i -> i+1 lies inside a segment, shape (n - 1,)."""
    new = np.zeros(n, bool)
    new[starts] = True
    return ~new[1:]


def check_sampling(time_s: np.ndarray, starts: np.ndarray, window_s: float,
                   rate_hz: float | None, tolerance: float, name: str, fmt: str
                   ) -> tuple[float, int]:
    """The sample rate and the samples per window, refusing a time column that does not
    fit them.

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        [s].
    starts : ndarray of int
        Segment starts (:func:`segment_starts`).
    window_s : float
        [s].
    rate_hz : float or None
        The logger's nominal sample rate [Hz]; None: one over the median step inside the
        segments.
    tolerance : float
        Largest relative deviation of a step from the sample period.
    name : str
        The time column as messages name it.
    fmt : str

    Returns
    -------
    (float, int)
        Sample rate [Hz] and samples per window, ``round(window_s * rate)``.

    Raises
    ------
    ValueError
        Naming the row: time not increasing inside a segment, a gap longer than a window
        inside a segment, a step off the sample period by more than ``tolerance``; or no
        two samples in any segment, a median step that contradicts ``rate_hz``, a rate
        giving fewer than :data:`MIN_WINDOW_SAMPLES` samples per window.
    """
    inside = _inside(time_s.size, starts)
    d = np.diff(time_s)
    bad = np.flatnonzero(inside & (d <= 0))
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(f"{name}, {row_name(i, fmt)}: time goes from {time_s[i - 1]:.9g} to "
                         f"{time_s[i]:.9g} s inside a segment; it must increase (the clock "
                         "does not jump there)")
    steps = d[inside]
    if steps.size == 0:
        raise ValueError(f"{name}: no segment holds two samples (the clock jumps at every "
                         "row?)")
    median = float(np.median(steps))
    fs = float(rate_hz) if rate_hz is not None else 1.0 / median
    if abs(median * fs - 1.0) > tolerance:
        raise ValueError(f"{name}: the median step is {median:.6g} s ({1 / median:.6g} Hz); "
                         f"sample_rate_hz={fs:g} Hz says {1 / fs:.6g} s")
    bad = np.flatnonzero(inside & (np.abs(d * fs - 1.0) > tolerance))
    if bad.size:
        i = int(bad[0]) + 1
        if d[i - 1] > window_s:
            raise ValueError(f"{name}, {row_name(i, fmt)}: a gap of {d[i - 1]:.6g} s inside a "
                             f"segment, longer than a window ({window_s:g} s), where the "
                             "clock does not jump: a new segment begins only where the clock "
                             "advances by more than a window")
        raise ValueError(f"{name}, {row_name(i, fmt)}: a step of {d[i - 1]:.6g} s; the sample "
                         f"rate {fs:.6g} Hz gives {1 / fs:.6g} s within rate_tolerance="
                         f"{tolerance:g} (irregular sampling: resample the recording first)")
    n_t = int(round(window_s * fs))
    if n_t < MIN_WINDOW_SAMPLES:
        raise ValueError(f"{name}: sample rate {fs:.6g} Hz too low for windows of "
                         f"{window_s:g} s: {n_t} samples per window, at least "
                         f"{MIN_WINDOW_SAMPLES}")
    return fs, n_t


def unwrap_segments(phi: np.ndarray, starts: np.ndarray, period: float) -> np.ndarray:
    """An angle made continuous inside each segment: a step of more than half a
    ``period`` (a single-turn sensor wrapping) is taken as the wrap. Values whose steps
    never wrap are returned unchanged, bit for bit.

    Parameters
    ----------
    phi : ndarray, shape (n,)
        Angle [rad or counts].
    starts : ndarray of int
        Segment starts.
    period : float
        One revolution in the unit of ``phi``.

    Returns
    -------
    ndarray, shape (n,)
    """
    d = np.diff(phi)
    corr = np.where(np.abs(d) > period / 2, -period * np.round(d / period), 0.0)
    corr[~_inside(phi.size, starts)] = 0.0
    if not corr.any():
        return phi.copy()
    cs = np.concatenate([[0.0], np.cumsum(corr)])
    seg = np.searchsorted(starts, np.arange(phi.size), side="right") - 1
    return phi + (cs - cs[starts[seg]])


def check_angle_turns(phi: np.ndarray, speed_rpm: np.ndarray, starts: np.ndarray,
                      resolution: float, name: str, fmt: str) -> None:
    """Refuse an angle that goes back by more than one count while the speed says the
    joint turns the other way (:data:`TURNING_RPM`).

    Parameters
    ----------
    phi : ndarray, shape (n,)
        Unwrapped angle [rad].
    speed_rpm : ndarray, shape (n,)
        Input speed [rpm].
    starts : ndarray of int
    resolution : float
        One count [rad].
    name : str
        The angle column as messages name it.
    fmt : str

    Raises
    ------
    ValueError
        Naming the row, the step and the speed.
    """
    d = np.diff(phi)
    s = np.sign(speed_rpm[1:])
    turning = (np.abs(speed_rpm[1:]) >= TURNING_RPM) & (np.sign(speed_rpm[:-1]) == s)
    bad = np.flatnonzero(_inside(phi.size, starts) & turning & (s * d < -1.01 * resolution))
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(f"{name}, {row_name(i, fmt)}: the angle steps by {d[i - 1]:+.6g} rad "
                         f"while the speed is {speed_rpm[i]:g} rpm (not monotone while the "
                         "joint turns: a sign convention, a wrapped angle of another period "
                         "or another column?)")


def _segment_sums(x: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Sum of ``x`` (one value per step, shape (n - 1,)) over each segment's steps."""
    n = x.size + 1
    ends = np.append(starts[1:], n) - 1  # last step index + 1 of each segment
    xp = np.append(x, 0.0)
    idx = np.ravel(np.column_stack([starts, np.maximum(ends, starts)]))
    sums = np.add.reduceat(xp, np.minimum(idx, x.size))[::2]
    return np.where(ends > starts, sums, 0.0)


def check_angle_speed(phi: np.ndarray, speed_rpm: np.ndarray, time_s: np.ndarray,
                      starts: np.ndarray, resolution: float, names: tuple[str, str],
                      fmt: str) -> None:
    """Refuse an angle whose advance over a segment disagrees with the integrated speed
    (:data:`ANGLE_AGREEMENT`); segments in which neither turns one revolution are not
    judged.

    Parameters
    ----------
    phi : ndarray, shape (n,)
        Unwrapped input angle [rad].
    speed_rpm, time_s : ndarray, shape (n,)
    starts : ndarray of int
    resolution : float
        One count [rad].
    names : (str, str)
        The angle and speed columns as messages name them.
    fmt : str

    Raises
    ------
    ValueError
        Naming the segment's rows, both advances and what usually causes it.
    """
    w = speed_rpm[:-1] * (2 * np.pi / 60.0) * np.diff(time_s)
    integ = _segment_sums(w, starts)
    adv = _segment_sums(np.diff(phi), starts)
    judged = np.maximum(np.abs(integ), np.abs(adv)) >= 2 * np.pi
    bad = np.flatnonzero(judged & (np.abs(adv - integ) > ANGLE_AGREEMENT * np.abs(integ)
                                   + 2 * resolution))
    if bad.size:
        k = int(bad[0])
        a = int(starts[k])
        b = int(starts[k + 1] - 1 if k + 1 < starts.size else phi.size - 1)
        raise ValueError(f"{names[0]}: over {row_name(a, fmt)} to {row_name(b, fmt)} the angle "
                         f"advances {adv[k]:.6g} rad, {names[1]} integrates to {integ[k]:.6g} "
                         f"rad (ratio {adv[k] / integ[k]:.3g}): a unit that cannot be right "
                         "(the speed in rad/s, the angle in degrees, counts_per_rev, or the "
                         "angle's sign)")


def check_output_angle(phi_out: np.ndarray, phi_in: np.ndarray, starts: np.ndarray,
                       ratio: float, resolution: float, name: str, fmt: str) -> None:
    """Refuse an output angle whose advance over a segment is not that of the input angle
    over ``-ratio`` (a rigid gear: φ_out = −φ_in / N, the convention of
    :mod:`swgsim.sensing.angles`), within :data:`ANGLE_AGREEMENT`; segments in which the
    input turns less than one revolution are not judged.

    Raises
    ------
    ValueError
        Naming the segment's rows and both advances.
    """
    adv_in = _segment_sums(np.diff(phi_in), starts)
    adv = _segment_sums(np.diff(phi_out), starts)
    want = -adv_in / ratio
    judged = np.abs(adv_in) >= 2 * np.pi
    bad = np.flatnonzero(judged & (np.abs(adv - want) > ANGLE_AGREEMENT * np.abs(want)
                                   + 2 * resolution))
    if bad.size:
        k = int(bad[0])
        a = int(starts[k])
        raise ValueError(f"{name}: over the segment from {row_name(a, fmt)} the output angle "
                         f"advances {adv[k]:.6g} rad, the input angle over -ratio "
                         f"({-ratio:g}) gives {want[k]:.6g} rad: a sign convention (the "
                         "output turns against the input: phi_out = -phi_in / N), "
                         "counts_per_rev or ratio that cannot be right")
