"""Compare a simulated recording with a measured one, signal by signal.

Both recordings are dicts of numpy arrays keyed ``"quantity [unit]"`` in SI units, as
written by the rig simulator (`pneumaquad.rig.simulate.RIG_COLUMNS`) and returned by
`pneumaquad.io.measured.read_measured`. The figures follow the thesis' validation in
section 4.3: RMSE over the whole run, also relative to a range (transcript lines
824-826), the lag between signals (line 818), and the time constants of first-order
fits to step responses, eq (4.3.1) (lines 812-814).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from .fits import FitError, fit_first_order
from .metrics import lag, max_abs_error, rmse, rmse_percent_of_range

__all__ = [
    "TIME_COLUMN",
    "AlignedRecordings",
    "SignalComparison",
    "align_recordings",
    "compare_recordings",
    "comparison_rows",
    "comparison_to_markdown",
]

TIME_COLUMN = "time [s]"
#: Columns never compared by default: the time axis and the input driving both runs.
_NOT_COMPARED = (TIME_COLUMN, "command [V]")

Recording = Mapping[str, np.ndarray]


@dataclass(frozen=True)
class AlignedRecordings:
    """Both recordings on one uniform time grid covering their overlap only.

    Attributes
    ----------
    time : numpy.ndarray
        The common grid [s], on the simulation's time axis.
    simulated, measured : dict of str to numpy.ndarray
        Linearly interpolated columns (every column but time) of each recording.
    time_offset : float
        Offset added to the measured time stamps [s].
    """

    time: np.ndarray
    simulated: dict[str, np.ndarray]
    measured: dict[str, np.ndarray]
    time_offset: float


@dataclass(frozen=True)
class SignalComparison:
    """Simulated-versus-measured figures of one signal (unit: that of the signal).

    Attributes
    ----------
    signal : str
        Column name, e.g. ``"cap pressure [Pa]"``.
    rmse : float
        Root-mean-square of simulated minus measured.
    rmse_percent : float
        RMSE in % of the span (given, or the measured range) [%].
    max_abs_error : float
        Largest absolute difference.
    lag : float
        Delay of the simulated signal behind the measured one [s] (negative: it leads).
    simulated_time_constant, measured_time_constant : float
        τ of first-order fits (thesis eq 4.3.1) after the step time [s]; NaN when no
        step time was given or the fit failed.
    simulated_range, measured_range : float
        max - min of each signal over the overlap.
    """

    signal: str
    rmse: float
    rmse_percent: float
    max_abs_error: float
    lag: float
    simulated_time_constant: float
    measured_time_constant: float
    simulated_range: float
    measured_range: float

    def as_row(self) -> dict[str, float | str]:
        """The figures as a dict whose keys name their units."""
        unit = _unit_of(self.signal)
        return {
            "signal": self.signal,
            f"RMSE [{unit}]": self.rmse,
            "RMSE [% of range]": self.rmse_percent,
            f"max abs error [{unit}]": self.max_abs_error,
            "lag [s]": self.lag,
            "simulated time constant [s]": self.simulated_time_constant,
            "measured time constant [s]": self.measured_time_constant,
            f"simulated range [{unit}]": self.simulated_range,
            f"measured range [{unit}]": self.measured_range,
        }


def align_recordings(
    simulated: Recording,
    measured: Recording,
    *,
    time_offset: float = 0.0,
    estimate_offset_from: str | None = None,
    max_offset: float | None = None,
    sample_time: float | None = None,
) -> AlignedRecordings:
    """Put both recordings on a common uniform time grid over their overlap.

    Parameters
    ----------
    simulated, measured : mapping of str to numpy.ndarray
        Recordings with a ``"time [s]"`` column (strictly increasing).
    time_offset : float
        Added to the measured time stamps [s]: a measured sample at ``t`` is compared
        with the simulated one at ``t + time_offset``.
    estimate_offset_from : str, optional
        Column used to estimate the offset automatically by cross-correlation (see
        `pneumaquad.analysis.metrics.lag`); the estimate is added to ``time_offset``.
    max_offset : float, optional
        Largest offset searched by the estimate [s]; default a quarter of the overlap.
    sample_time : float, optional
        Spacing of the common grid [s]; default the coarser median spacing of the two.

    Returns
    -------
    AlignedRecordings

    Raises
    ------
    ValueError
        Without a time column, on non-increasing time, or when the recordings do not
        overlap in time.
    """
    sim_time = _time_of(simulated, "simulated")
    meas_time = _time_of(measured, "measured") + time_offset
    if sample_time is None:
        sample_time = max(float(np.median(np.diff(sim_time))), float(np.median(np.diff(meas_time))))
    if not sample_time > 0:
        raise ValueError(f"sample time must be greater than 0, got {sample_time!r}")
    aligned = _resample(simulated, sim_time, measured, meas_time, sample_time, time_offset)
    if estimate_offset_from is None:
        return aligned
    for name, recording in (("simulated", simulated), ("measured", measured)):
        if estimate_offset_from not in recording:
            raise ValueError(
                f"cannot estimate the time offset from {estimate_offset_from!r}: the "
                f"{name} recording has no such column; it has {sorted(recording)}"
            )
    delay = lag(
        aligned.time,
        aligned.simulated[estimate_offset_from],
        aligned.measured[estimate_offset_from],
        max_lag=max_offset,
    )
    if not math.isfinite(delay):
        raise ValueError(
            f"cannot estimate the time offset from {estimate_offset_from!r}: the signal is "
            "constant over the overlap"
        )
    offset = time_offset + delay
    return _resample(
        simulated, sim_time, measured, meas_time - time_offset + offset, sample_time, offset
    )


def compare_recordings(
    simulated: Recording,
    measured: Recording,
    *,
    signals: Sequence[str] | None = None,
    time_offset: float = 0.0,
    estimate_offset_from: str | None = None,
    max_offset: float | None = None,
    sample_time: float | None = None,
    spans: Mapping[str, float] | None = None,
    step_time: float | None = None,
    max_lag: float | None = None,
) -> tuple[list[SignalComparison], AlignedRecordings]:
    """Per-signal comparison of a simulated run with a measured one.

    Parameters
    ----------
    simulated, measured : mapping of str to numpy.ndarray
        The two recordings.
    signals : sequence of str, optional
        Columns to compare; default every column both have except time and command.
    time_offset, estimate_offset_from, max_offset, sample_time
        Alignment, see `align_recordings`.
    spans : mapping of str to float, optional
        Span per signal for the RMSE percentage (e.g. the stroke for position [m]);
        signals without one use the measured range.
    step_time : float, optional
        If the run is a step response, the step instant [s] on the simulated time axis;
        first-order fits from there on give each signal's time constants.
    max_lag : float, optional
        Largest lag searched per signal [s]; default a quarter of the overlap.

    Returns
    -------
    comparisons : list of SignalComparison
        One per signal, in the order of ``signals``.
    aligned : AlignedRecordings
        The resampled data the figures were computed on.
    """
    aligned = align_recordings(
        simulated,
        measured,
        time_offset=time_offset,
        estimate_offset_from=estimate_offset_from,
        max_offset=max_offset,
        sample_time=sample_time,
    )
    if signals is None:
        signals = [name for name in simulated if name in measured and name not in _NOT_COMPARED]
    missing = [
        f"{name!r} (missing from the {which} recording)"
        for name in signals
        for which, recording in (("simulated", simulated), ("measured", measured))
        if name not in recording
    ]
    if missing:
        raise ValueError("cannot compare " + ", ".join(missing))
    spans = spans or {}
    comparisons = []
    for name in signals:
        sim, meas = aligned.simulated[name], aligned.measured[name]
        comparisons.append(
            SignalComparison(
                signal=name,
                rmse=rmse(sim, meas),
                rmse_percent=rmse_percent_of_range(sim, meas, spans.get(name)),
                max_abs_error=max_abs_error(sim, meas),
                lag=lag(aligned.time, sim, meas, max_lag=max_lag),
                simulated_time_constant=_time_constant(aligned.time, sim, step_time),
                measured_time_constant=_time_constant(aligned.time, meas, step_time),
                simulated_range=float(np.ptp(sim)),
                measured_range=float(np.ptp(meas)),
            )
        )
    return comparisons, aligned


def comparison_to_markdown(comparisons: Sequence[SignalComparison], digits: int = 4) -> str:
    """Render comparisons as a Markdown table, one row per signal.

    Parameters
    ----------
    comparisons : sequence of SignalComparison
        Rows to render.
    digits : int
        Significant digits of the numbers.

    Returns
    -------
    str
        The table, ending with a newline. Units appear in the "unit" column; NaN is
        shown as "–".
    """
    header = (
        "| signal | unit | RMSE | RMSE [% of range] | max abs error | lag [s] "
        "| τ simulated [s] | τ measured [s] |"
    )
    lines = [header, "|" + "---|" * 8]
    for row in comparisons:
        values = (
            row.rmse,
            row.rmse_percent,
            row.max_abs_error,
            row.lag,
            row.simulated_time_constant,
            row.measured_time_constant,
        )
        cells = [_strip_unit(row.signal), _unit_of(row.signal)]
        cells += [_format(value, digits) for value in values]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def comparison_rows(comparisons: Sequence[SignalComparison]) -> list[dict[str, float | str]]:
    """The comparisons as plain dicts (all dataclass fields)."""
    return [asdict(row) for row in comparisons]


def _time_of(recording: Recording, name: str) -> np.ndarray:
    if TIME_COLUMN not in recording:
        raise ValueError(f"the {name} recording has no {TIME_COLUMN!r} column")
    times = np.asarray(recording[TIME_COLUMN], dtype=float)
    if times.size < 2 or not np.all(np.diff(times) > 0):
        raise ValueError(f"the {name} recording's time must have 2+ increasing samples")
    return times


def _resample(
    simulated: Recording,
    sim_time: np.ndarray,
    measured: Recording,
    meas_time: np.ndarray,
    sample_time: float,
    offset: float,
) -> AlignedRecordings:
    start, stop = max(sim_time[0], meas_time[0]), min(sim_time[-1], meas_time[-1])
    if stop - start < sample_time:
        raise ValueError(
            f"the recordings do not overlap in time: simulated {sim_time[0]:g}-"
            f"{sim_time[-1]:g} s, measured {meas_time[0]:g}-{meas_time[-1]:g} s "
            f"(offset {offset:g} s applied)"
        )
    count = math.floor((stop - start) / sample_time * (1 + 1e-12)) + 1
    grid = start + sample_time * np.arange(count)
    grid[-1] = min(grid[-1], stop)  # no extrapolation past the overlap from round-off

    def columns(recording: Recording, times: np.ndarray) -> dict[str, np.ndarray]:
        return {
            name: np.interp(grid, times, np.asarray(values, dtype=float))
            for name, values in recording.items()
            if name != TIME_COLUMN
        }

    return AlignedRecordings(
        grid, columns(simulated, sim_time), columns(measured, meas_time), float(offset)
    )


def _time_constant(time: np.ndarray, values: np.ndarray, step_time: float | None) -> float:
    if step_time is None:
        return math.nan
    try:
        return fit_first_order(time, values, start_time=step_time).value("time constant")
    except FitError:
        return math.nan


def _unit_of(signal: str) -> str:
    if signal.endswith("]") and "[" in signal:
        return signal[signal.rindex("[") + 1 : -1]
    return "-"


def _strip_unit(signal: str) -> str:
    if signal.endswith("]") and "[" in signal:
        return signal[: signal.rindex("[")].strip()
    return signal


def _format(value: float, digits: int) -> str:
    return "–" if not math.isfinite(value) else f"{value:.{digits}g}"
