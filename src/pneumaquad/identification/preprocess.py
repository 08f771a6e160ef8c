"""Shared signal preparation for parameter identification from rig recordings.

A recording (simulated, `pneumaquad.io.run_folder.read_recording`, or measured,
`pneumaquad.io.measured.read_measured`) is turned into filtered position, velocity,
acceleration and pressures, and into the forces of the piston force balance, eq 4.1.11:

    m·a = F_pneumatic + F_gravity - F_friction (+ F_end_stop at the stops),
    F_pneumatic = P_cap·A_cap - P_rod·A_rod - P_atm·A_rod_section.

Filtering follows the thesis's offline processing (zero-phase Chebyshev type II low-pass,
velocity as the filtered gradient of position, thesis 4.2.1 and App. A.2); the cut-offs
are this project's defaults and can be changed with `FilterSettings`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pneumaquad.analysis import find_steps, lowpass_filter, velocity_from_position
from pneumaquad.analysis.segmentation import StepSegment
from pneumaquad.core.physics.force import gravity_force, piston_force
from pneumaquad.params.schema import RigSetup

__all__ = [
    "REQUIRED_COLUMNS",
    "FilterSettings",
    "IdentificationError",
    "PreparedSignals",
    "prepare_signals",
    "select_step",
]

#: Recording columns every identification needs.
REQUIRED_COLUMNS = (
    "time [s]",
    "command [V]",
    "position [m]",
    "cap pressure [Pa]",
    "rod pressure [Pa]",
)


class IdentificationError(ValueError):
    """The data cannot give the requested estimate (missing columns, no step, no motion)."""


@dataclass(frozen=True)
class FilterSettings:
    """Stop-band edges of the zero-phase low-pass filters [Hz]; None skips a filter.

    Attributes
    ----------
    position_cutoff : float or None
        Position filter before differentiation [Hz].
    velocity_cutoff : float
        Filter of the position gradient [Hz].
    acceleration_cutoff : float
        Filter of the velocity gradient [Hz].
    pressure_cutoff : float or None
        Filter of both chamber pressures [Hz].
    """

    position_cutoff: float | None = 100.0
    velocity_cutoff: float = 60.0
    acceleration_cutoff: float = 40.0
    pressure_cutoff: float | None = 100.0


@dataclass(frozen=True)
class PreparedSignals:
    """Filtered signals and force-balance terms of one recording (SI units).

    Attributes
    ----------
    time : numpy.ndarray
        [s].
    command : numpy.ndarray
        Valve command as recorded (unfiltered) [V].
    position, velocity, acceleration : numpy.ndarray
        Filtered [m], [m/s], [m/s^2].
    cap_pressure, rod_pressure : numpy.ndarray
        Filtered absolute pressures [Pa].
    pneumatic_force : numpy.ndarray
        Eq 4.1.11 without friction, positive extending [N].
    gravity_force : float
        Weight of the moving mass along +x [N].
    moving_mass : float
        Load plus piston mass [kg].
    stroke : float
        Cylinder stroke [m]; the end stops are at 0 and stroke.
    """

    time: np.ndarray
    command: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    cap_pressure: np.ndarray
    rod_pressure: np.ndarray
    pneumatic_force: np.ndarray
    gravity_force: float
    moving_mass: float
    stroke: float

    @property
    def friction_force(self) -> np.ndarray:
        """Friction from the force balance away from the stops, F_pn + F_g - m·a [N].

        Positive values oppose positive velocity (the sign convention of
        `pneumaquad.core.physics.friction`). Wrong while a stop pushes on the piston.
        """
        return self.pneumatic_force + self.gravity_force - self.moving_mass * self.acceleration


def _require_columns(recording: Mapping[str, np.ndarray]) -> None:
    missing = [name for name in REQUIRED_COLUMNS if name not in recording]
    if missing:
        raise IdentificationError(
            f"the recording lacks the columns {missing}; it has {sorted(recording)}"
        )


def prepare_signals(
    recording: Mapping[str, np.ndarray],
    setup: RigSetup,
    filters: FilterSettings | None = None,
) -> PreparedSignals:
    """Filter a recording and compute the terms of the piston force balance (eq 4.1.11).

    Parameters
    ----------
    recording : mapping of str to numpy.ndarray
        Columns ``"time [s]"``, ``"command [V]"``, ``"position [m]"``,
        ``"cap pressure [Pa]"``, ``"rod pressure [Pa]"`` (absolute), uniformly sampled.
    setup : RigSetup
        Cylinder areas, moving mass, orientation, gravity and atmospheric pressure.
    filters : FilterSettings, optional
        Filter cut-offs; `FilterSettings()` by default.

    Returns
    -------
    PreparedSignals

    Raises
    ------
    IdentificationError
        For missing columns, or a recording too short or not uniformly sampled.
    """
    _require_columns(recording)
    filters = filters or FilterSettings()
    time = np.asarray(recording["time [s]"], dtype=float)
    try:
        position = np.asarray(recording["position [m]"], dtype=float)
        if filters.position_cutoff is not None:
            position = lowpass_filter(time, position, filters.position_cutoff)
        velocity = velocity_from_position(time, position, filters.velocity_cutoff)
        acceleration = lowpass_filter(
            time, np.gradient(velocity, time, edge_order=2), filters.acceleration_cutoff
        )
        pressures = []
        for name in ("cap pressure [Pa]", "rod pressure [Pa]"):
            values = np.asarray(recording[name], dtype=float)
            if filters.pressure_cutoff is not None:
                values = lowpass_filter(time, values, filters.pressure_cutoff)
            pressures.append(values)
    except ValueError as error:
        raise IdentificationError(f"cannot filter the recording: {error}") from error
    cylinder, rig = setup.actuator.cylinder, setup.rig
    moving_mass = rig.load_mass + cylinder.piston_mass
    # The compiled eq 4.1.11 is plain arithmetic; its Python original takes arrays.
    force = getattr(piston_force, "py_func", piston_force)(
        pressures[0],
        pressures[1],
        setup.actuator.gas.atmospheric_pressure,
        cylinder.cap_area,
        cylinder.rod_area,
        cylinder.rod_cross_section,
    )
    return PreparedSignals(
        time=time,
        command=np.asarray(recording["command [V]"], dtype=float),
        position=position,
        velocity=velocity,
        acceleration=acceleration,
        cap_pressure=pressures[0],
        rod_pressure=pressures[1],
        pneumatic_force=force,
        gravity_force=float(gravity_force(moving_mass, rig.gravity, rig.orientation_angle)),
        moving_mass=moving_mass,
        stroke=cylinder.stroke,
    )


def select_step(
    time: np.ndarray,
    command: np.ndarray,
    step_time: float | None = None,
    command_threshold: float = 0.05,
) -> StepSegment:
    """The command step to analyse: the one at ``step_time``, or the first one.

    Parameters
    ----------
    time, command : numpy.ndarray
        Sample times [s] and valve command [V].
    step_time : float, optional
        Time of the step [s]; the step starting nearest to it is taken.
    command_threshold : float
        Smallest command jump counted as a step [V].

    Returns
    -------
    StepSegment
        From the change instant to the next change (or the end of the recording).

    Raises
    ------
    IdentificationError
        If the command holds no step.
    """
    segments = find_steps(time, command, command_threshold)
    if not segments:
        raise IdentificationError(
            f"the command never jumps by more than {command_threshold:g} V: no step to analyse"
        )
    if step_time is None:
        return segments[0]
    return min(segments, key=lambda segment: abs(segment.start_time - step_time))
