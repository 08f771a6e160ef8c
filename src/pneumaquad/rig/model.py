"""Rig parameters, initial state and actuator banks for the compiled rig kernel."""

from collections.abc import Sequence

import numpy as np

from pneumaquad.core import layout
from pneumaquad.core.actuator import initial_state, new_parameters, pack_parameters
from pneumaquad.core.bank import ActuatorBank
from pneumaquad.core.control.pid import controller_gains
from pneumaquad.core.physics.force import gravity_force
from pneumaquad.params.schema import RigSetup

__all__ = [
    "pack_rig_fields",
    "pack_rig_parameters",
    "rig_bank",
    "rig_controller_gains",
    "rig_initial_state",
    "rig_start",
]


def pack_rig_fields(setup: RigSetup, record: np.void) -> np.void:
    """Fill the rig fields (:data:`~pneumaquad.core.layout.RIG_PARAMETER_FIELDS`: load and
    stops) of a parameter record whose actuator fields are packed already.

    The moving mass is the load plus the piston/rod mass [kg]; gravity [N] acts along the
    rod at the rig's orientation (thesis 4.2.1: the board could be clamped in any
    orientation).
    """
    rig = setup.rig
    moving_mass = rig.load_mass + setup.actuator.cylinder.piston_mass
    record["moving_mass"] = moving_mass
    record["gravity_force"] = gravity_force(moving_mass, rig.gravity, rig.orientation_angle)
    record["end_stop_stiffness"] = rig.end_stop_stiffness
    record["end_stop_damping"] = rig.end_stop_damping
    record["spacer"] = 1 if rig.spacer else 0
    return record


def pack_rig_parameters(setup: RigSetup, out: np.ndarray | None = None) -> np.ndarray:
    """Kernel parameters of a rig: an array of one
    :data:`~pneumaquad.core.layout.ACTUATOR_PARAMETERS_DTYPE` record, the actuator plus
    the rig fields (:func:`pack_rig_fields`), every field by name (``out`` filled when
    given)."""
    params = new_parameters(1) if out is None else out
    pack_rig_fields(setup, pack_parameters(setup.actuator, params[0]))
    return params


def rig_start(setup: RigSetup) -> tuple[float, float, float]:
    """The rig's initial piston position [m] (full extension with the spacer) and cap and
    rod chamber pressures [Pa]."""
    rig = setup.rig
    position = setup.actuator.cylinder.stroke if rig.spacer else rig.initial_position
    return position, rig.initial_cap_pressure, rig.initial_rod_pressure


def rig_initial_state(setup: RigSetup, params: np.ndarray) -> np.ndarray:
    """Initial kernel state of a rig, an array of one
    :data:`~pneumaquad.core.layout.ACTUATOR_STATE_DTYPE` record: the rig's initial
    position [m] and chamber pressures [Pa], at rest."""
    position, cap, rod = rig_start(setup)
    state = np.zeros(1, layout.ACTUATOR_STATE_DTYPE)
    initial_state(params[0], position, cap, rod, out=state[0])
    return state


def rig_controller_gains(setup: RigSetup) -> np.void:
    """PID gains of the rig's parameter file, with the valve's offset and range."""
    return controller_gains(setup.controller, setup.actuator.valve)


def rig_bank(setups: RigSetup | Sequence[RigSetup]) -> ActuatorBank:
    """An actuator bank of N independent rigs, one per setup, each with its own supply,
    at its initial state (:func:`rig_start`), the rig fields packed
    (:func:`pack_rig_fields`; the bank's setters keep them)."""
    setups = [setups] if isinstance(setups, RigSetup) else list(setups)
    bank = ActuatorBank([s.actuator for s in setups], [s.controller for s in setups],
                        shared_supply=False)
    for setup, record in zip(setups, bank.params, strict=True):
        pack_rig_fields(setup, record)
    starts = np.array([rig_start(setup) for setup in setups])
    bank.reset(starts[:, 0], starts[:, 1], starts[:, 2])
    return bank
