"""Named layouts are complete and unambiguous: every field of a packed structure is filled
by the code that packs it, names are unique, and the named views of a simulation are the
arrays they name."""

from __future__ import annotations

import numpy as np

from pneumaquad.core import layout
from pneumaquad.core.actuator import supply_state
from pneumaquad.params import load_rig, load_robot
from pneumaquad.rig.model import pack_rig_parameters, rig_initial_state
from pneumaquad.rig.simulate import (
    RIG_COLUMNS,
    RIG_RECORDING,
    RIG_ROW_DTYPE,
    new_rows,
    simulate_rig,
    write_row,
)
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.coupling import JOINT_CONTROL_DTYPE, LINKAGE_DTYPE, SEAL_DTYPE
from pneumaquad.robot.simulation import RobotSimulation


def test_rig_recording_names_are_unique_and_every_column_is_written() -> None:
    fields = [field for field, _ in RIG_RECORDING]
    assert len(set(fields)) == len(fields) and len(set(RIG_COLUMNS)) == len(RIG_COLUMNS)
    assert RIG_ROW_DTYPE.names == tuple(fields)
    setup = load_rig("thesis-rig", ['supply.model="tank"'])  # every column finite
    params = pack_rig_parameters(setup)
    state = rig_initial_state(setup, params)
    records, rows = new_rows(1)
    rows[:] = np.nan  # a field write_row leaves alone stays NaN
    write_row(records, 0, 0.001, 5.5, 0.02, params[0], state[0],
              np.ones(layout.N_OUTPUTS), supply_state(setup.actuator))
    unwritten = [name for name, value in zip(RIG_COLUMNS, rows[0], strict=True)
                 if not np.isfinite(value)]
    assert unwritten == []
    assert records[0]["command"] == rows[0, RIG_COLUMNS.index("command [V]")] == 5.5
    recording = simulate_rig(setup, np.full(50, 0.02), closed_loop=True).recording
    assert tuple(recording) == RIG_COLUMNS


def test_robot_records_are_filled_from_their_sources() -> None:
    robot = build_robot(load_robot("crr-quadruped"), "fixed")
    simulation = RobotSimulation(robot)
    for dtype in (LINKAGE_DTYPE, SEAL_DTYPE, JOINT_CONTROL_DTYPE):
        assert len(set(dtype.names)) == len(dtype.names)
    for i, joint_type in enumerate(robot.joint_types):
        linkage = robot.linkages[joint_type]
        for field in LINKAGE_DTYPE.names:
            assert simulation.linkage[i][field] == getattr(linkage, field), field
        friction = robot.actuators[joint_type].friction  # Stribeck-tanh: every field set
        seal = simulation.seal[i]
        assert seal["static_force"] == friction.static_force
        assert seal["coulomb_force"] == friction.coulomb_force
        assert seal["stribeck_velocity"] == friction.stribeck_velocity
        assert seal["stribeck_exponent"] == friction.stribeck_exponent
        assert seal["viscous_coefficient"] == friction.viscous_coefficient


def test_named_views_are_the_arrays_they_name() -> None:
    """The bundles handed to the compiled step hold the simulation's own arrays under the
    same names (a swap of two same-shaped arrays in a bundle fails here)."""
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
    data, model = simulation.data, simulation.model
    sources = {
        "tendon_length": data.ten_length, "tendon_velocity": data.ten_velocity,
        "control": data.ctrl, "tendon_frictionloss": model.tendon_frictionloss,
        "tendon_damping": model.tendon_damping,
        "tendon_ids": simulation.robot.tendon_id, "actuator_ids": simulation.robot.actuator_id,
        "settings": simulation.joint_control,
    }
    bundles = (simulation.mujoco, simulation.cylinders, simulation.actuators,
               simulation.controllers, simulation.trace)
    for bundle in bundles:
        for name, array in bundle._asdict().items():
            source = sources.get(name, getattr(simulation, name, None))
            assert source is not None, name
            assert array is source or (
                array.__array_interface__["data"][0] == source.__array_interface__["data"][0]
                and array.shape == source.shape), f"{type(bundle).__name__}.{name}"
