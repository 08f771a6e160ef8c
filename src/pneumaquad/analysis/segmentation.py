"""Split a step train into its steps and compute step figures for each.

A step train is a piecewise-constant command or reference, such as the closed-loop step
series of thesis Figure 28 (section 4.3) or the step commands of Figure 38. A change
instant is where the command moves by more than a threshold between two samples;
consecutive such samples (a transition spread over a few samples) form one change.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .metrics import step_metrics

__all__ = ["StepSegment", "find_steps", "metrics_per_step"]


@dataclass(frozen=True)
class StepSegment:
    """One step of a step train: from a change instant to the next (or the end).

    Attributes
    ----------
    start_index : int
        Index of the first sample at (or moving to) the new level.
    end_index : int
        Index one past the last sample of the segment (Python slice end).
    start_time : float
        ``time[start_index]`` [s].
    end_time : float
        Time of the last sample of the segment [s].
    initial_level : float
        Command level before the change: median over the preceding segment.
    final_level : float
        Command level after the change: median over the segment after the transition.
    """

    start_index: int
    end_index: int
    start_time: float
    end_time: float
    initial_level: float
    final_level: float

    @property
    def step_size(self) -> float:
        """Final minus initial level (unit of the command)."""
        return self.final_level - self.initial_level


def find_steps(time: ArrayLike, command: ArrayLike, threshold: float) -> list[StepSegment]:
    """Detect the change instants of a piecewise-constant signal.

    Parameters
    ----------
    time : array_like
        Sample times [s].
    command : array_like
        The step train (any unit).
    threshold : float
        A change is a jump of more than this between consecutive samples (unit of the
        command); choose it above the noise and below the smallest step.

    Returns
    -------
    list of StepSegment
        One segment per change, in time order; the part before the first change is not a
        step and is not returned.

    Raises
    ------
    ValueError
        For mismatched lengths, non-finite samples or a threshold that is not positive.
    """
    times = np.asarray(time, dtype=float).ravel()
    values = np.asarray(command, dtype=float).ravel()
    if times.shape != values.shape:
        raise ValueError(f"time has {times.size} samples but the command has {values.size}")
    if not np.all(np.isfinite(values)):
        raise ValueError("the command contains NaN or infinite values")
    if not threshold > 0:
        raise ValueError(f"threshold must be greater than 0, got {threshold!r}")
    jumps = np.abs(np.diff(values)) > threshold
    # Sample i starts a transition when the jump into it is large and the jump into i - 1 not.
    starts = np.nonzero(jumps & ~np.concatenate([[False], jumps[:-1]]))[0] + 1
    boundaries = [*starts.tolist(), values.size]
    segments = []
    previous_start = 0
    for number, start in enumerate(starts):
        end = boundaries[number + 1]
        settled_start = start
        while settled_start < end - 1 and jumps[settled_start]:
            settled_start += 1  # skip the rest of a multi-sample transition
        segments.append(
            StepSegment(
                start_index=int(start),
                end_index=int(end),
                start_time=float(times[start]),
                end_time=float(times[end - 1]),
                initial_level=float(np.median(values[previous_start:start])),
                final_level=float(np.median(values[settled_start:end])),
            )
        )
        previous_start = settled_start
    return segments


def metrics_per_step(
    time: ArrayLike,
    response: ArrayLike,
    command: ArrayLike,
    threshold: float,
    *,
    levels_from: str = "command",
    settling_band: float = 0.02,
    rise_fractions: Sequence[float] = (0.1, 0.9),
    unit: str = "-",
) -> list[dict[str, float]]:
    """Step figures of the response for every step of the command.

    Parameters
    ----------
    time : array_like
        Sample times [s].
    response : array_like
        Response samples, e.g. position [m].
    command : array_like
        The step train that drove the response.
    threshold : float
        Change threshold of `find_steps` (unit of the command).
    levels_from : {"command", "response"}
        ``"command"``: the target levels are the command levels (a closed-loop reference
        in the response's unit), and the steady-state error is reported. ``"response"``:
        the levels come from the response itself (its value at the change and its mean
        over the last 10 % of the segment), as for open-loop responses to a valve command.
    settling_band : float
        Settling band half-width as a fraction of the step size.
    rise_fractions : sequence of two floats
        Lower and upper fraction of the step for the rise time.
    unit : str
        Unit of the response, used in the keys.

    Returns
    -------
    list of dict
        Per step: ``"step"`` (1-based number), ``"start time [s]"``, ``"end time [s]"``,
        ``"initial command"``, ``"final command"``, then the keys of
        `pneumaquad.analysis.metrics.step_metrics`.
    """
    if levels_from not in ("command", "response"):
        raise ValueError(f"levels_from must be 'command' or 'response', got {levels_from!r}")
    times = np.asarray(time, dtype=float).ravel()
    values = np.asarray(response, dtype=float).ravel()
    if values.shape != times.shape:
        raise ValueError(f"time has {times.size} samples but the response has {values.size}")
    table = []
    for number, segment in enumerate(find_steps(times, command, threshold), start=1):
        window = slice(segment.start_index, segment.end_index)
        levels = {}
        if levels_from == "command":
            levels = {"initial_level": segment.initial_level, "final_level": segment.final_level}
        row: dict[str, float] = {
            "step": number,
            "start time [s]": segment.start_time,
            "end time [s]": segment.end_time,
            "initial command": segment.initial_level,
            "final command": segment.final_level,
        }
        if segment.end_index - segment.start_index >= 2:
            row.update(
                step_metrics(
                    times[window],
                    values[window],
                    step_time=segment.start_time,
                    settling_band=settling_band,
                    rise_fractions=rise_fractions,
                    unit=unit,
                    **levels,
                )
            )
        table.append(row)
    return table
