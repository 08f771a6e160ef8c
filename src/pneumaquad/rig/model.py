"""Rig parameters and initial state for the compiled rig kernel."""

import numpy as np

from pneumaquad.core import layout
from pneumaquad.core.actuator import initial_state, new_parameters, pack_parameters
from pneumaquad.core.control.pid import controller_gains
from pneumaquad.core.physics.force import gravity_force
from pneumaquad.params.schema import RigSetup


def pack_rig_parameters(setup: RigSetup, out: np.ndarray | None = None) -> np.ndarray:
    """Kernel parameters of a rig: an array of one
    :data:`~pneumaquad.core.layout.ACTUATOR_PARAMETERS_DTYPE` record, the actuator plus
    the rig fields (load and stops), every field by name (``out`` filled when given).

    The moving mass is the load plus the piston/rod mass [kg]; gravity [N] acts along the
    rod at the rig's orientation (thesis 4.2.1: the board could be clamped in any
    orientation).
    """
    params = new_parameters(1) if out is None else out
    record = pack_parameters(setup.actuator, params[0])
    rig = setup.rig
    moving_mass = rig.load_mass + setup.actuator.cylinder.piston_mass
    record["moving_mass"] = moving_mass
    record["gravity_force"] = gravity_force(moving_mass, rig.gravity, rig.orientation_angle)
    record["end_stop_stiffness"] = rig.end_stop_stiffness
    record["end_stop_damping"] = rig.end_stop_damping
    record["spacer"] = 1 if rig.spacer else 0
    return params


def rig_initial_state(setup: RigSetup, params: np.ndarray) -> np.ndarray:
    """Initial kernel state of a rig, an array of one
    :data:`~pneumaquad.core.layout.ACTUATOR_STATE_DTYPE` record: the rig's initial
    position [m] and chamber pressures [Pa], at rest."""
    rig = setup.rig
    position = setup.actuator.cylinder.stroke if rig.spacer else rig.initial_position
    state = np.zeros(1, layout.ACTUATOR_STATE_DTYPE)
    initial_state(params[0], position, rig.initial_cap_pressure, rig.initial_rod_pressure,
                  out=state[0])
    return state


def rig_controller_gains(setup: RigSetup) -> np.void:
    """PID gains of the rig's parameter file, with the valve's offset and range."""
    return controller_gains(setup.controller, setup.actuator.valve)
