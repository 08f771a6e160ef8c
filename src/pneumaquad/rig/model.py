"""Rig parameters and initial state for the compiled rig kernel."""

import numpy as np

from pneumaquad.core import layout
from pneumaquad.core.actuator import initial_state, pack_parameters
from pneumaquad.core.control.pid import controller_gains
from pneumaquad.core.physics.force import gravity_force
from pneumaquad.params.schema import RigSetup


def pack_rig_parameters(setup: RigSetup) -> np.ndarray:
    """Kernel parameter array (1, N_PARAMETERS) of a rig: actuator plus load and stops.

    The moving mass is the load plus the piston/rod mass; gravity acts along the rod at
    the rig's orientation (thesis 4.2.1: the board could be clamped in any orientation).
    """
    row = pack_parameters(setup.actuator)
    rig = setup.rig
    moving_mass = rig.load_mass + setup.actuator.cylinder.piston_mass
    row[layout.P_MOVING_MASS] = moving_mass
    row[layout.P_GRAVITY_FORCE] = gravity_force(moving_mass, rig.gravity, rig.orientation_angle)
    row[layout.P_STOP_STIFFNESS] = rig.end_stop_stiffness
    row[layout.P_STOP_DAMPING] = rig.end_stop_damping
    row[layout.P_SPACER] = 1.0 if rig.spacer else 0.0
    return row[np.newaxis, :]


def rig_initial_state(setup: RigSetup, params: np.ndarray) -> np.ndarray:
    """Initial kernel state (1, N_STATES): the rig's initial position and pressures, at rest."""
    rig = setup.rig
    position = setup.actuator.cylinder.stroke if rig.spacer else rig.initial_position
    state = initial_state(params[0], position, rig.initial_cap_pressure, rig.initial_rod_pressure)
    return state[np.newaxis, :]


def rig_controller_gains(setup: RigSetup) -> np.void:
    """PID gains of the rig's parameter file, with the valve's offset and range."""
    return controller_gains(setup.controller, setup.actuator.valve)
