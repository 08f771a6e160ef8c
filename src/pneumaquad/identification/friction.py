"""Friction identification from open-loop step recordings (thesis 4.2.2.4).

The thesis reads friction off the chamber pressures of open-loop steps (Fig. 12): the
pressures build up until the piston breaks away, which shows as a peak (the "stiction
peak"); the net pneumatic force there, less the load's weight, is the static friction
F_S. After the peak the piston runs at a roughly constant velocity and the net force is
Coulomb plus viscous friction, F_C·sign(v) + C_V·v (eq 4.2.4, sliding branch), solved
from points at several velocities. Samples at the end stops are left out, where the stop's
reaction enters the force balance (thesis Fig. 16, grey regions).

Here the force balance (eq 4.1.11, see `pneumaquad.identification.preprocess`) also takes
the inertia m·a into account. The least-squares fits of the friction laws live in
`pneumaquad.identification.friction_fits` and are re-exported here.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from pneumaquad.analysis.fits import FitResult
from pneumaquad.params.schema import RigSetup

from .friction_fits import (
    STRIBECK_TANH_PARAMETERS,
    fit_coulomb_viscous,
    fit_stribeck_tanh,
    stribeck_tanh_curve,
)
from .preprocess import FilterSettings, IdentificationError, prepare_signals, select_step

__all__ = [
    "STRIBECK_TANH_PARAMETERS",
    "FrictionPoints",
    "StictionEstimate",
    "fit_coulomb_viscous",
    "fit_stribeck_tanh",
    "kinetic_friction_points",
    "stiction_from_step",
    "stribeck_tanh_curve",
    "summarize_stiction",
]


@dataclass(frozen=True)
class StictionEstimate:
    """Static friction read off one open-loop step.

    Attributes
    ----------
    static_force : float
        F_S estimate [N], >= 0 when the breakaway was seen.
    direction : int
        +1 for an extending, -1 for a retracting motion.
    onset_time : float
        First instant the speed stays above the threshold [s].
    peak_time : float
        Instant of the stiction peak used [s].
    force_rate : float
        Rate of the net force just before the peak [N/s]; times the sample interval it
        is the resolution of the estimate (fast steps resolve the peak poorly).
    clear_peak : bool
        Whether a peak of the friction estimate was found near the onset at a low speed;
        without a peak the value at the onset is returned. Use only clear estimates.
    speed_at_peak : float
        Filtered speed at the peak [m/s].
    step_voltage : float
        Valve command after the step [V].
    """

    static_force: float
    direction: int
    onset_time: float
    peak_time: float
    force_rate: float
    clear_peak: bool
    step_voltage: float
    speed_at_peak: float


@dataclass(frozen=True)
class FrictionPoints:
    """Friction samples from the force balance during sliding.

    Attributes
    ----------
    time, position, velocity, acceleration, friction : numpy.ndarray
        Of the selected samples [s, m, m/s, m/s^2, N]; friction opposes positive velocity
        when positive.
    """

    time: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    friction: np.ndarray

    @staticmethod
    def concatenate(parts: Iterable[FrictionPoints]) -> FrictionPoints:
        """Join samples of several recordings."""
        parts = list(parts)
        if not parts:
            empty = np.empty(0)
            return FrictionPoints(empty, empty, empty, empty, empty)
        return FrictionPoints(
            *(
                np.concatenate([getattr(part, name) for part in parts])
                for name in ("time", "position", "velocity", "acceleration", "friction")
            )
        )


def _onset(speed_along: np.ndarray, threshold: float, hold: int) -> int | None:
    """First index from which the speed stays above threshold for ``hold`` samples."""
    above = speed_along > threshold
    run = 0
    for index, flag in enumerate(above):
        run = run + 1 if flag else 0
        if run >= hold:
            return index - hold + 1
    return None


def stiction_from_step(
    recording: Mapping[str, np.ndarray],
    setup: RigSetup,
    *,
    step_time: float | None = None,
    velocity_threshold: float = 0.01,
    hold_time: float = 0.005,
    search_before: float = 0.02,
    search_after: float = 0.03,
    min_prominence: float = 0.5,
    max_peak_speed: float = 0.07,
    include_inertia: bool = True,
    filters: FilterSettings | None = None,
) -> StictionEstimate:
    """Static friction F_S at the breakaway of an open-loop step (thesis 4.2.2.4, Fig. 12).

    The friction estimate F_pn + F_g - m·a (eq 4.1.11 solved for friction; F_g is
    m·g·sin(orientation)) is taken in the direction of motion; its first local maximum
    near the motion onset is the stiction peak. Slow steps (a few tenths of a volt from
    the valve offset) resolve it; fast ones do not (``clear_peak`` is False).

    Parameters
    ----------
    recording : mapping of str to numpy.ndarray
        Rig recording (see `pneumaquad.identification.preprocess.REQUIRED_COLUMNS`).
    setup : RigSetup
        Areas, moving mass, orientation, gravity, stroke.
    step_time : float, optional
        Time of the step [s]; by default the first command step.
    velocity_threshold : float
        Speed above which the piston counts as moving [m/s]; above the velocity noise.
    hold_time : float
        The speed must stay above the threshold this long [s].
    search_before, search_after : float
        Window around the onset searched for the peak [s].
    min_prominence : float
        How far the force must fall on both sides of a peak to count [N]; above the
        force noise after filtering.
    max_peak_speed : float
        Largest speed at the peak for a clear breakaway [m/s]. In fast steps the force
        keeps rising with the viscous term and the breakaway transient, and a peak there
        overestimates F_S (by 10-60 % in simulated thesis-rig steps with peaks at
        0.09 m/s and faster; slow steps peaked at 0.01-0.05 m/s).
    include_inertia : bool
        Subtract m·a (the thesis subtracted only the weight).
    filters : FilterSettings, optional
        Filter cut-offs.

    Returns
    -------
    StictionEstimate

    Raises
    ------
    IdentificationError
        If there is no step or the piston does not move after it.
    """
    signals = prepare_signals(recording, setup, filters)
    step = select_step(signals.time, signals.command, step_time)
    start, end = step.start_index, step.end_index
    interval = float(np.mean(np.diff(signals.time)))
    hold = max(1, round(hold_time / interval))
    velocity = signals.velocity[start:end]
    # The direction of the fastest motion; the first threshold crossing may be a ripple
    # of the zero-phase filter ahead of a fast step.
    direction = 1 if velocity[np.argmax(np.abs(velocity))] > 0 else -1
    onset = _onset(direction * velocity, velocity_threshold, hold)
    if onset is None:
        raise IdentificationError(
            f"the piston does not move after the step at {step.start_time:g} s "
            f"(speed never stays above {velocity_threshold:g} m/s)"
        )
    force = signals.pneumatic_force + signals.gravity_force
    if include_inertia:
        force = force - signals.moving_mass * signals.acceleration
    along = direction * force[start:end]
    first = max(0, onset - round(search_before / interval))
    last = min(along.size, onset + round(search_after / interval) + 1)
    window = along[first:last]
    from scipy.signal import find_peaks  # SciPy loads on first use: it is slow to import
    peaks, _ = find_peaks(window, prominence=min_prominence)
    peaks = peaks[window[peaks] > 0.0]
    peak = first + int(peaks[0]) if peaks.size else onset
    speed = abs(float(velocity[peak]))
    before = max(peak - hold, 0)
    rate = (along[peak] - along[before]) / max(peak - before, 1) / interval
    return StictionEstimate(
        static_force=float(along[peak]),
        direction=direction,
        onset_time=float(signals.time[start + onset]),
        peak_time=float(signals.time[start + peak]),
        force_rate=float(rate),
        clear_peak=bool(peaks.size > 0 and speed <= max_peak_speed),
        speed_at_peak=speed,
        step_voltage=float(step.final_level),
    )


def kinetic_friction_points(
    recording: Mapping[str, np.ndarray],
    setup: RigSetup,
    *,
    min_speed: float = 0.01,
    max_acceleration: float = 2.0,
    end_margin: float = 0.002,
    time_range: tuple[float, float] | None = None,
    filters: FilterSettings | None = None,
) -> FrictionPoints:
    """Friction samples while the piston slides (thesis 4.2.2.4: constant-velocity phase).

    Friction = F_pn + F_g - m·a from the force balance (eq 4.1.11). Kept are samples with
    speed above ``min_speed``, ``|a| <= max_acceleration`` (near-constant velocity) and a
    position at least ``end_margin`` from both end stops (0 and the stroke), where the
    stop's reaction would be counted as friction.

    Parameters
    ----------
    recording : mapping of str to numpy.ndarray
        Rig recording, any number of steps (or closed-loop motion).
    setup : RigSetup
        Areas, moving mass, orientation, gravity, stroke.
    min_speed : float
        [m/s]; keep it above the Stribeck region when fitting Coulomb-viscous friction.
    max_acceleration : float
        [m/s^2]; ``numpy.inf`` keeps accelerating samples too.
    end_margin : float
        Distance from the end stops within which samples are dropped [m]; 0 keeps all.
    time_range : (float, float), optional
        Only samples with start <= t <= end [s].
    filters : FilterSettings, optional
        Filter cut-offs.

    Returns
    -------
    FrictionPoints
    """
    signals = prepare_signals(recording, setup, filters)
    keep = np.abs(signals.velocity) > min_speed
    keep &= np.abs(signals.acceleration) <= max_acceleration
    keep &= (signals.position >= end_margin) & (signals.position <= signals.stroke - end_margin)
    if time_range is not None:
        keep &= (signals.time >= time_range[0]) & (signals.time <= time_range[1])
    return FrictionPoints(
        time=signals.time[keep],
        position=signals.position[keep],
        velocity=signals.velocity[keep],
        acceleration=signals.acceleration[keep],
        friction=signals.friction_force[keep],
    )


def summarize_stiction(estimates: Iterable[StictionEstimate], clear_only: bool = True) -> FitResult:
    """One F_S from several steps: the median of the (clear) estimates.

    The thesis reported the spread of stiction over many steps (Fig. 13) and used one
    value. The standard error given is that of the median, 1.2533·s/sqrt(n), with s the
    sample standard deviation (0 for a single estimate).

    Parameters
    ----------
    estimates : iterable of StictionEstimate
        From `stiction_from_step`.
    clear_only : bool
        Use only estimates with ``clear_peak``.

    Returns
    -------
    FitResult
        ``"static_force [N]"``; ``details`` holds the values used per direction.

    Raises
    ------
    IdentificationError
        If no estimate is usable.
    """
    used = [item for item in estimates if item.clear_peak or not clear_only]
    if not used:
        raise IdentificationError(
            "no step showed a clear stiction peak; use slower steps (commands a few tenths "
            "of a volt from the valve offset)"
        )
    values = np.array([item.static_force for item in used])
    spread = float(np.std(values, ddof=1)) if values.size > 1 else 0.0
    median = float(np.median(values))
    return FitResult(
        name="stiction peaks",
        parameters={"static_force [N]": median},
        standard_errors={"static_force [N]": 1.2533 * spread / math.sqrt(values.size)},
        r_squared=math.nan,
        residual_rms=float(np.sqrt(np.mean((values - median) ** 2))),
        n_points=int(values.size),
        residual_unit="N",
        details={
            "extending [N]": [item.static_force for item in used if item.direction > 0],
            "retracting [N]": [item.static_force for item in used if item.direction < 0],
        },
    )
