"""Closed-loop recordings for controller identification, and what a controller fit returns.

A closed-loop recording of the rig holds the reference position r, the piston position y
and, where it was logged, the valve command u on a uniform time base. It follows the
simulator's sampling convention (`pneumaquad.rig.simulate`): the command of a row was set
at the start of the period that ends at the row's time stamp, from the reference of that
row and the position the controller saw then; with the controller period T_c and a
measurement delay of D control steps, the command of the row at time t was computed from
the position at t - (1 + D)·T_c. The fits report that lag and the delay it implies.

The controller is the project's PID (`pneumaquad.core.control.pid.pid_update`):

    u = u_0 + Kp·e + I - Kd·ẏ_f,   e = r - y,   I = Σ Ki·e·T (clamped, frozen in saturation),

with ẏ_f the measured rate through a first-order filter of time constant τ_d.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pneumaquad.analysis.filters import sample_rate_of
from pneumaquad.analysis.fits import FitResult

from .preprocess import IdentificationError

__all__ = [
    "COMMAND_COLUMN",
    "CONTROLLER_COLUMNS",
    "GAIN_KEYS",
    "METHODS",
    "MIN_REFERENCE_RANGE",
    "START_STATES",
    "ClosedLoopRecording",
    "ControllerFit",
    "closed_loop_recording",
]

#: The methods: chosen from the recordings, on the command, by output error.
METHODS = ("auto", "command", "output-error")
#: Choices of the output-error simulation's start state: the parameter set's
#: ``rig.initial_*`` state, at rest at the first recorded row, or whichever of the two fits
#: the first horizon better with the start gains.
START_STATES = ("auto", "parameters", "recording")

#: Columns every controller fit needs.
CONTROLLER_COLUMNS = ("time [s]", "reference position [m]", "position [m]")
#: The valve command, which the direct (regression) method needs.
COMMAND_COLUMN = "command [V]"
#: Fit keys of the three gains, in the controller table's names and units.
GAIN_KEYS = (
    "proportional_gain [V/m]",
    "integral_gain [V/(m*s)]",
    "derivative_gain [V*s/m]",
)
#: Fit key of the derivative filter time constant.
FILTER_KEY = "derivative_filter_time_constant [s]"
#: Fit key of a fitted valve offset (direct method).
OFFSET_KEY = "offset_voltage [V]"
#: Smallest range of the reference position that excites the loop [m].
MIN_REFERENCE_RANGE = 1e-4
#: Fewest samples of a recording.
MIN_SAMPLES = 50


@dataclass(frozen=True)
class ClosedLoopRecording:
    """The columns of one closed-loop recording a controller fit reads (SI).

    Attributes
    ----------
    time : numpy.ndarray
        Sample times [s], uniform.
    reference : numpy.ndarray
        Reference position [m].
    position : numpy.ndarray
        Piston position [m].
    command : numpy.ndarray or None
        Valve command [V], held over the period before each time stamp; None when the
        recording has none.
    period : float
        Sample period [s].
    cap_pressure, rod_pressure : numpy.ndarray or None
        Absolute chamber pressures [Pa] where recorded (the output-error fit starts its
        simulation from the first ones).
    """

    time: np.ndarray
    reference: np.ndarray
    position: np.ndarray
    command: np.ndarray | None
    period: float
    cap_pressure: np.ndarray | None = None
    rod_pressure: np.ndarray | None = None

    @property
    def samples(self) -> int:
        """Number of rows."""
        return int(self.time.size)


def _column(recording: Mapping[str, np.ndarray], name: str, label: str) -> np.ndarray:
    values = np.asarray(recording[name], dtype=float).ravel()
    bad = ~np.isfinite(values)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise IdentificationError(
            f"{label}: {name!r} has {int(bad.sum())} non-finite values (the first at row "
            f"{first}); a controller fit needs every sample")
    return values


def closed_loop_recording(
    recording: Mapping[str, np.ndarray], label: str = "the recording"
) -> ClosedLoopRecording:
    """Check a recording for a controller fit and take the columns it needs.

    Parameters
    ----------
    recording : mapping
        Columns keyed ``"quantity [unit]"`` in SI (a run folder's recording, or a lab file
        through `pneumaquad.io.measured.read_measured` with a ``reference position``
        column in its mapping).
    label : str
        How messages name the recording (its file).

    Returns
    -------
    ClosedLoopRecording

    Raises
    ------
    IdentificationError
        Missing columns (naming those there are), fewer than 50 rows, non-finite values,
        time stamps that are not uniform (spacing varying by more than 0.1 %), or a
        reference that does not move by at least `MIN_REFERENCE_RANGE` (a constant
        reference does not excite the loop: the gains cannot be told apart).
    """
    missing = [name for name in CONTROLLER_COLUMNS if name not in recording]
    if missing:
        raise IdentificationError(
            f"{label} lacks the columns {missing} that a controller fit needs; it has "
            f"{sorted(recording)} (a lab file maps its reference with a 'reference "
            "position' column in the mapping)")
    time = _column(recording, "time [s]", label)
    if time.size < MIN_SAMPLES:
        raise IdentificationError(
            f"{label} has {time.size} rows; a controller fit needs at least {MIN_SAMPLES}")
    try:
        period = 1.0 / sample_rate_of(time)
    except ValueError as error:
        raise IdentificationError(
            f"{label}: the time base is unusable: {error}. The controller is reconstructed "
            "sample by sample, so the time stamps must be uniform (resample first)") from error
    reference = _column(recording, "reference position [m]", label)
    position = _column(recording, "position [m]", label)
    span = float(np.ptp(reference))
    if span < MIN_REFERENCE_RANGE:
        raise IdentificationError(
            f"{label}: the reference position is constant (it spans {span * 1e3:.3g} mm, "
            f"less than {MIN_REFERENCE_RANGE * 1e3:g} mm): a constant reference does not "
            "excite the closed loop, so the gains cannot be told apart; record steps, a "
            "sine or a chirp of the reference")
    command = (_column(recording, COMMAND_COLUMN, label)
               if COMMAND_COLUMN in recording else None)
    pressures = [
        _column(recording, name, label) if name in recording else None
        for name in ("cap pressure [Pa]", "rod pressure [Pa]")
    ]
    return ClosedLoopRecording(time, reference, position, command, period, *pressures)


@dataclass(frozen=True)
class ControllerFit:
    """An identified controller.

    Attributes
    ----------
    fit : FitResult
        The gains (`GAIN_KEYS`) and, where fitted, the derivative filter time constant
        and the valve offset, with standard errors; ``problems`` lists failed checks.
    method : str
        ``"command"`` (regression on the recorded command) or ``"output error"``
        (re-simulation of the closed loop).
    filter_time_constant : float
        Derivative filter time constant [s], fitted or held.
    filter_fitted : bool
        Whether the data determined it (else it is the parameter set's value).
    measurement_delay : float
        Delay of the position the controller saw, in whole control steps of the
        parameter set [s] (what ``controller.measurement_delay`` gets).
    delay_fitted : bool
        Whether it was searched (else given).
    lag : float
        Lag from the position a command was computed from to the command's time stamp
        [s]: (1 + D)·T_c for a delay of D control steps of T_c.
    sample_period, control_step : float
        The recording's sample period and the parameter set's controller period [s].
    notes : tuple of str
        What the fit decided and why, one sentence each (shown by the command line).
    details : mapping
        Extra figures (the delay search's residuals, the samples used ...).
    """

    fit: FitResult
    method: str
    filter_time_constant: float
    filter_fitted: bool
    measurement_delay: float
    delay_fitted: bool
    lag: float
    sample_period: float
    control_step: float
    notes: tuple[str, ...] = ()
    details: Mapping[str, Any] = field(default_factory=dict)

    @property
    def failed(self) -> bool:
        """True when the fit's checks say its values are not to be trusted."""
        return self.fit.failed

    def gains(self) -> tuple[float, float, float]:
        """(Kp [V/m], Ki [V/(m s)], Kd [V s/m])."""
        return tuple(float(self.fit.parameters[key]) for key in GAIN_KEYS)  # type: ignore[return-value]

    def updates(self) -> dict[str, Any]:
        """Parameter-file updates ``{"controller.key": "value unit"}``: the gains, the
        filter time constant where fitted and the measurement delay where searched."""
        updates: dict[str, Any] = {}
        for key in GAIN_KEYS:
            name, unit = key.split(" [")
            updates[f"controller.{name}"] = f"{float(self.fit.parameters[key])!r} {unit[:-1]}"
        if self.filter_fitted:
            updates["controller.derivative_filter_time_constant"] = (
                f"{self.filter_time_constant!r} s")
        if self.delay_fitted:
            updates["controller.measurement_delay"] = f"{self.measurement_delay!r} s"
        return updates


def delay_from_lag(lag: float, control_step: float) -> float:
    """The measurement delay [s] of a lag [s]: ``(lag / control_step - 1)`` whole control
    steps, at least none."""
    steps = max(0, round(lag / control_step - 1.0))
    return steps * control_step


def position_noise(recordings: Sequence[ClosedLoopRecording]) -> float:
    """Standard deviation of white noise on the recorded positions [m], estimated from
    their second differences: 1.4826 · median |Δ²y - median Δ²y| / √6 (the median
    absolute deviation, robust against the samples where the piston accelerates)."""
    second = np.concatenate([np.diff(r.position, 2) for r in recordings])
    deviation = np.median(np.abs(second - np.median(second)))
    return float(1.4826 * deviation / math.sqrt(6.0))
