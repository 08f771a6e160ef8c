"""The actuator bank: setters keep the validated parameters and the packed records in
sync, banks never share memory, and a bank holds exactly the arrays the robot and the
rig built themselves before it existed."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.core.actuator import (
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.bank import ActuatorBank
from pneumaquad.core.control.pid import (
    PID_GAINS_DTYPE,
    controller_gains,
    new_pid_state,
)
from pneumaquad.core.layout import RIG_PARAMETER_FIELDS
from pneumaquad.params import ParameterError, load_rig, load_robot
from pneumaquad.rig.model import (
    pack_rig_parameters,
    rig_bank,
    rig_controller_gains,
    rig_initial_state,
)
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.simulation import RobotSimulation

BANK_ARRAYS = ("params", "state", "supply", "outputs", "gains", "pid_state",
               "base_gain_scale", "gain_scale", "references", "open_loop_voltage", "commands")


@pytest.fixture(scope="module")
def robot():
    return build_robot(load_robot("crr-quadruped"), "fixed")


def _robot_bank(robot, supply: str | None = None) -> ActuatorBank:
    actuators = [robot.actuators[t] for t in robot.joint_types]
    controllers = [getattr(robot.parameters.controller, t) for t in robot.joint_types]
    return ActuatorBank(actuators, controllers, supply_model=supply)


def _in_sync(bank: ActuatorBank) -> None:
    """The packed records are the packing of the validated objects (rig fields aside)."""
    packed = pack_parameter_array(list(bank.actuators))
    for name in packed.dtype.names:
        if name not in RIG_PARAMETER_FIELDS:
            np.testing.assert_array_equal(bank.params[name], packed[name], err_msg=name)
    for i, (controller, actuator) in enumerate(zip(bank.controllers, bank.actuators,
                                                   strict=True)):
        assert bank.gains[i] == controller_gains(controller, actuator.valve)
        assert bank.base_gain_scale[i] == getattr(controller, "gain_scale", 1.0)


# --- setters --------------------------------------------------------------------------
def test_supply_pressure_setter_updates_objects_and_records(robot) -> None:
    bank = _robot_bank(robot)
    bank.set_supply_pressure(5.0e5)
    assert all(a.supply.supply_pressure == 5.0e5 for a in bank.actuators)
    np.testing.assert_array_equal(bank.params["supply_pressure"], 5.0e5)
    _in_sync(bank)
    per_joint = np.linspace(4e5, 6e5, 12)
    bank.set_supply_pressure(per_joint)
    assert [a.supply.supply_pressure for a in bank.actuators] == list(per_joint)
    _in_sync(bank)
    bank.set_supply_pressure(3e5, which=[0, 5])
    assert bank.params["supply_pressure"][[0, 5]].tolist() == [3e5, 3e5]
    assert bank.params["supply_pressure"][1] == per_joint[1]
    _in_sync(bank)


@pytest.mark.parametrize(("value", "expected"), [
    (2e8, "at most 100 MPa"),
    (-1.0, "greater than 0 Pa"),
    (1.0e5, "above exhaust_pressure"),
    (float("nan"), "not finite"),
])
def test_supply_pressure_out_of_range_is_refused_naming_the_key(robot, value, expected) -> None:
    bank = _robot_bank(robot)
    before, objects = bank.params.copy(), bank.actuators
    with pytest.raises(ParameterError, match=expected) as refused:
        bank.set_supply_pressure(value)
    assert refused.value.problems[0].key == "supply.supply_pressure"
    assert "supply.supply_pressure" in str(refused.value)
    assert np.array_equal(bank.params, before) and bank.actuators == objects


def test_tank_supply_pressure_stays_below_the_tank(robot) -> None:
    bank = _robot_bank(robot, supply="tank")
    assert all(a.supply.model == "tank" for a in bank.actuators)
    tank = bank.actuators[0].supply.tank_initial_pressure
    with pytest.raises(ParameterError, match="tank_initial_pressure"):
        bank.set_supply_pressure(tank * 1.01)


def test_gain_setters_keep_tables_and_records_in_sync(robot) -> None:
    bank = _robot_bank(robot)
    bank.pid_state["integral"] = 0.25
    bank.set_gains(proportional_gain=123.0, integral_gain=[float(i) for i in range(12)])
    assert [c.proportional_gain for c in bank.controllers] == [123.0] * 12
    assert bank.gains["integral_gain"].tolist() == list(range(12))
    np.testing.assert_array_equal(bank.pid_state["integral"], 0.25)  # memory kept
    _in_sync(bank)
    bank.set_gain_scale(0.5, which=np.array([t == "beta" for t in robot.joint_types]))
    betas = [i for i, t in enumerate(robot.joint_types) if t == "beta"]
    assert bank.base_gain_scale[betas].tolist() == [0.5] * 4
    assert bank.gain_scale[betas].tolist() == [0.5] * 4
    _in_sync(bank)
    with pytest.raises(ParameterError, match=r"gain_scale: 200\.0 should be"):
        bank.set_gain_scale(200.0)
    with pytest.raises(ParameterError, match=r"derivative_gain: -1\.0 should be"):
        bank.set_gains(derivative_gain=-1.0)
    with pytest.raises(ParameterError, match="not a PID field"):
        bank.set_gains(gain=1.0)
    _in_sync(bank)


def test_rig_bank_keeps_its_rig_fields_and_scales_without_a_gain_scale_field() -> None:
    setup = load_rig("thesis-rig", ["rig.load_mass=\"2 kg\""])
    bank = rig_bank(setup)
    rig_fields = bank.params[list(RIG_PARAMETER_FIELDS)].copy()
    bank.set_supply_pressure(4.0e5)
    assert bank.params[list(RIG_PARAMETER_FIELDS)] == rig_fields
    assert bank.actuators[0].supply.supply_pressure == bank.params[0]["supply_pressure"]
    bank.set_gain_scale(2.0)  # a rig's controller table has no gain_scale: range-checked
    assert bank.gain_scale[0] == 2.0
    with pytest.raises(ParameterError, match="gain_scale"):
        bank.set_gain_scale(-1.0)


def test_references_voltages_reset_and_readouts() -> None:
    setups = [load_rig("thesis-rig"), load_rig("thesis-rig", ['supply.supply_pressure="40 psig"'])]
    bank = rig_bank(setups)
    assert not bank.shared_supply and bank.supply.shape == (2,)
    bank.set_references([0.01, 0.02])
    bank.set_open_loop_voltages(5.5, which=1)
    assert bank.references.tolist() == [0.01, 0.02]
    assert bank.open_loop_voltage[1] == 5.5
    with pytest.raises(ValueError, match="finite"):
        bank.set_references(np.nan)
    with pytest.raises(ValueError, match="3 values for 2 actuators"):
        bank.set_references([0.0, 0.0, 0.0])
    bank.pid_state["integral"] = 1.0
    bank.supply["drawn_mass"] = 1.0
    bank.reset([0.005, 0.01], 2.0e5, 3.0e5)
    np.testing.assert_array_equal(bank.chamber_pressures(), [[2e5, 3e5], [2e5, 3e5]])
    assert bank.positions().tolist() == [0.005, 0.01]
    assert bank.air_consumed() == 0.0 and np.all(bank.pid_state["integral"] == 0.0)
    bank.reset(0.0)  # midway between each rig's supply and exhaust
    p = bank.params
    np.testing.assert_array_equal(bank.chamber_pressures()[:, 0],
                                  0.5 * (p["supply_pressure"] + p["exhaust_pressure"]))
    assert bank.supply_pressure(1) == p[1]["supply_pressure"] < p[0]["supply_pressure"]
    assert bank.atmospheric_pressure() == p[0]["atmospheric_pressure"]
    assert bank.forces().shape == (2,) and bank.air_consumed_per_actuator().shape == (2,)


# --- ownership --------------------------------------------------------------------------
def test_two_banks_never_share_memory(robot) -> None:
    first, second = _robot_bank(robot), _robot_bank(robot)
    for name in BANK_ARRAYS:
        a, b = getattr(first, name), getattr(second, name)
        assert not np.shares_memory(a, b), name
        for other in BANK_ARRAYS:
            if other != name:
                assert not np.shares_memory(a, getattr(first, other)), (name, other)
    first.set_supply_pressure(4e5)
    first.set_gains(proportional_gain=1.0)
    first.state["cap_pressure"] = 1.0
    assert second.params["supply_pressure"][0] != 4e5
    assert second.gains["proportional_gain"][0] != 1.0
    assert second.state["cap_pressure"][0] == 0.0
    assert second.actuators[0].supply.supply_pressure != 4e5


def test_bundles_are_the_banks_arrays(robot) -> None:
    bank = _robot_bank(robot)
    for bundle in (bank.actuator_arrays, bank.controller_arrays):
        for name, array in bundle._asdict().items():
            assert array is getattr(bank, name), name


def test_simulation_attributes_are_the_banks_and_cannot_be_rebound(robot) -> None:
    simulation = RobotSimulation(robot)
    bank = simulation.bank
    for name in ("params", "state", "supply", "outputs", "gains", "pid_state",
                 "base_gain_scale", "gain_scale", "open_loop_voltage", "commands"):
        assert getattr(simulation, name) is getattr(bank, name), name
    assert simulation.reference_positions is bank.references
    with pytest.raises(AttributeError, match="held by"):
        simulation.params = bank.params.copy()


# --- the arrays the robot and the rig built before the bank ------------------------------
@pytest.mark.parametrize("supply", [None, "tank"])
def test_robot_bank_equals_the_arrays_the_robot_built(robot, supply) -> None:
    """The construction RobotSimulation.__init__ did itself until the bank held it."""
    actuators = [robot.actuators[t] for t in robot.joint_types]
    controllers = [getattr(robot.parameters.controller, t) for t in robot.joint_types]
    first = robot.actuators["alpha"]
    if supply is not None and supply != first.supply.model:
        first = first.model_copy(update={"supply": first.supply.model_copy(
            update={"model": supply})})
    expected = {
        "params": pack_parameter_array(actuators),
        "supply": supply_state(first),
        "outputs": new_outputs(12),
        "gains": np.array([controller_gains(c, a.valve)
                           for c, a in zip(controllers, actuators, strict=True)],
                          dtype=PID_GAINS_DTYPE),
        "pid_state": new_pid_state(12),
        "base_gain_scale": np.array([c.gain_scale for c in controllers]),
        "gain_scale": np.array([c.gain_scale for c in controllers]),
        "open_loop_voltage": pack_parameter_array(actuators)["offset_voltage"],
        "commands": pack_parameter_array(actuators)["offset_voltage"],
        "references": np.zeros(12),
    }
    bank = _robot_bank(robot, supply)
    for name, array in expected.items():
        got = getattr(bank, name)
        assert got.dtype == array.dtype and np.array_equal(got, array), name
    simulation = RobotSimulation(robot, supply=supply)  # the same, through the robot
    for name in ("params", "supply", "gains", "base_gain_scale"):
        assert np.array_equal(getattr(simulation.bank, name), expected[name]), name


def test_rig_bank_equals_the_arrays_the_rig_built() -> None:
    setup = load_rig("thesis-rig", ['supply.model="tank"', "rig.spacer=true"])
    bank = rig_bank(setup)
    params = pack_rig_parameters(setup)
    assert np.array_equal(bank.params, params)
    assert np.array_equal(bank.state, rig_initial_state(setup, params))
    assert np.array_equal(bank.supply, supply_state(setup.actuator))
    assert bank.gains[0] == rig_controller_gains(setup)
    assert np.array_equal(bank.pid_state, new_pid_state(1))


def test_a_bank_needs_a_controller_per_actuator(robot) -> None:
    with pytest.raises(ValueError, match="one controller per actuator"):
        ActuatorBank([robot.actuators["alpha"]] * 2, [robot.parameters.controller.alpha])


@pytest.mark.parametrize("supply", ["ideal", "tank"])
def test_the_air_count_restarts_only_for_a_regulated_supply(robot, supply) -> None:
    simulation = RobotSimulation(robot, supply=supply)
    simulation.set_pose(np.zeros(robot.joint_count))
    simulation.command_angles(np.full(robot.joint_count, 0.2))
    simulation.step(200)
    drawn = simulation.air_consumed()
    assert drawn > 0.0
    simulation.restart_clock()
    assert simulation.time == 0.0 and simulation.steps_taken == 0
    if supply == "ideal":
        assert simulation.air_consumed() == 0.0
        assert np.all(simulation.air_consumed_per_joint() == 0.0)
    else:  # the tank's pressure has dropped by what was drawn: the count stays
        assert simulation.air_consumed() == drawn
