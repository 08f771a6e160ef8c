"""Rig inputs: open-loop valve commands and closed-loop position references on a time grid.

Every function returns samples at t_k = k·dt, k = 0 … n-1, n = round(duration/dt).
"""

from collections.abc import Sequence
from pathlib import Path

import numpy as np

#: Most samples of a recorded reference on the control grid (as the command line's limit
#: of 10 million control steps per run).
MAX_REFERENCE_SAMPLES = 10_000_000


def time_grid(duration: float, control_step: float) -> np.ndarray:
    """Sample times t_k = k·dt covering [0, duration) [s]."""
    count = round(duration / control_step)
    return np.arange(count) * control_step


def constant(value: float, count: int) -> np.ndarray:
    """A held value for ``count`` control steps."""
    return np.full(count, float(value))


def thesis_step_command(
    step_voltage: float,
    offset_voltage: float,
    min_voltage: float,
    max_voltage: float,
    control_step: float,
    step_time: float = 5.0,
    duration: float = 10.0,
) -> np.ndarray:
    """Open-loop step protocol of thesis 4.2.3: saturate the other way, then step.

    The valve is held at the saturation opposite to the step (relative to the offset)
    until step_time, then set to step_voltage until duration (5 s + 5 s in the thesis).

    Returns
    -------
    numpy.ndarray
        Valve command per control step [V].
    """
    times = time_grid(duration, control_step)
    before = min_voltage if step_voltage >= offset_voltage else max_voltage
    return np.where(times < step_time, before, step_voltage).astype(float)


def step_train(levels: Sequence[float], dwell: float, control_step: float) -> np.ndarray:
    """Position reference visiting each level for ``dwell`` seconds [m]."""
    per_level = round(dwell / control_step)
    return np.repeat(np.asarray(levels, dtype=float), per_level)


def trapezoid(
    low: float,
    high: float,
    ramp_time: float,
    hold_time: float,
    cycles: int,
    control_step: float,
) -> np.ndarray:
    """Trapezoidal position reference: hold low, ramp up, hold high, ramp down [m]."""
    period = 2.0 * (ramp_time + hold_time)
    times = time_grid(period * cycles, control_step)
    phase = np.mod(times, period)
    knots_t = [0.0, hold_time, hold_time + ramp_time, 2 * hold_time + ramp_time, period]
    knots_y = [low, low, high, high, low]
    return np.interp(phase, knots_t, knots_y)


def sine(
    mean: float, amplitude: float, frequency: float, duration: float, control_step: float
) -> np.ndarray:
    """Sinusoidal position reference mean + A·sin(2π f t) [m]; frequency in Hz."""
    times = time_grid(duration, control_step)
    return mean + amplitude * np.sin(2.0 * np.pi * frequency * times)


def chirp(
    mean: float,
    amplitude: float,
    start_frequency: float,
    end_frequency: float,
    duration: float,
    control_step: float,
) -> np.ndarray:
    """Linear chirp position reference from start to end frequency [Hz] over duration [m]."""
    times = time_grid(duration, control_step)
    rate = (end_frequency - start_frequency) / duration
    phase = 2.0 * np.pi * (start_frequency * times + 0.5 * rate * times**2)
    return mean + amplitude * np.sin(phase)


class RecordedReferenceError(ValueError):
    """A recorded reference file cannot be used."""


def recorded_reference(
    path: Path,
    time_column: str,
    value_column: str,
    value_scale: float,
    control_step: float,
    time_scale: float = 1.0,
) -> np.ndarray:
    """Position reference read from a CSV or MATLAB .mat file, resampled to the control grid.

    Parameters
    ----------
    path : Path
        CSV with a header row, or .mat (v5; variables named by the columns).
    time_column, value_column : str
        Column (or variable) names of time and position.
    value_scale : float
        Factor converting the file's position unit to metres.
    control_step : float
        Output sample time [s].
    time_scale : float
        Factor converting the file's time unit to seconds (1e-3 for milliseconds).

    Returns
    -------
    numpy.ndarray
        Reference [m] on t_k = k·dt from the file's first time to its last.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordedReferenceError(f"reference file {str(path)!r} does not exist")
    if path.suffix.lower() == ".mat":
        try:
            from scipy.io import loadmat  # SciPy loads on first use: it is slow to import
            contents = loadmat(path, squeeze_me=True)
        except (NotImplementedError, ValueError) as error:
            raise RecordedReferenceError(f"{path}: cannot read MATLAB file ({error})") from error
        columns = {
            k: np.atleast_1d(v).astype(float) for k, v in contents.items() if not k.startswith("__")
        }
    else:
        table = np.genfromtxt(path, delimiter=",", names=True, dtype=float, encoding="utf-8")
        columns = {name: np.atleast_1d(table[name]) for name in table.dtype.names}
    for name in (time_column, value_column):
        if name not in columns:
            raise RecordedReferenceError(
                f"{path}: column {name!r} not found; columns are {sorted(columns)}"
            )
    times = columns[time_column] * time_scale
    values = columns[value_column] * value_scale
    if times.size < 2 or not np.all(np.isfinite(times)) or not np.all(np.isfinite(values)):
        raise RecordedReferenceError(f"{path}: needs at least two finite samples")
    if np.any(np.diff(times) <= 0):
        raise RecordedReferenceError(f"{path}: time column {time_column!r} is not increasing")
    samples = (times[-1] - times[0]) / control_step
    if samples > MAX_REFERENCE_SAMPLES:
        raise RecordedReferenceError(
            f"{path}: time column {time_column!r} spans {times[-1] - times[0]:.4g} s, "
            f"{samples:.3g} control steps of {control_step:g} s; expected at most "
            f"{MAX_REFERENCE_SAMPLES:,}"
        )
    grid = times[0] + time_grid(times[-1] - times[0], control_step)
    return np.interp(grid, times, values)
