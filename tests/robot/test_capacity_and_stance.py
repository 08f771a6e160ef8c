"""Supply capacity from statics, the stance verdict, phase gates and the staged rise."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pneumaquad.locomotion.capacity import (
    InsufficientSupplyError,
    check_supply,
    cylinder_demands,
    least_supply_for_force,
    rise_requirement,
    stall_forces,
    supply_requirements,
)
from pneumaquad.params import ParameterError, load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import Phase, run_phases
from pneumaquad.robot.scenarios import STANDING_ANGLES, stand_up_phases, standing_height
from pneumaquad.robot.simulation import RobotSimulation
from pneumaquad.robot.stance_check import stance_verdict
from pneumaquad.robot.stand_up import STAGED_ALPHA, alpha_swing_signs

PSI = 6894.757293168
ATMOSPHERE = 14.7 * PSI  # the actuator files' 14.7 psia


def _simulation(*overrides: str) -> RobotSimulation:
    return RobotSimulation(build_robot(load_robot("crr-quadruped", list(overrides)),
                                       "quadruped"))


@pytest.fixture(scope="module")
def simulation() -> RobotSimulation:
    return _simulation()


def test_robot_supply_pressure_reaches_every_cylinder_and_is_validated():
    robot = build_robot(load_robot("crr-quadruped", ['actuators.supply_pressure="45 psig"']),
                        "quadruped")
    for actuator in robot.actuators.values():
        assert actuator.supply.supply_pressure == pytest.approx(45 * PSI + ATMOSPHERE)
    with pytest.raises(ParameterError, match=r"actuators\.supply_pressure"):
        load_robot("crr-quadruped", ['actuators.supply_pressure="45 kg"'])


def test_stall_forces_are_the_pressure_balance_less_coulomb_friction(simulation):
    actuator = simulation.robot.actuators["gamma"]
    cylinder, supply = actuator.cylinder, actuator.supply
    friction = actuator.friction.coulomb_force
    extending, retracting = stall_forces(actuator)
    assert extending == pytest.approx(
        supply.supply_pressure * cylinder.cap_area - supply.exhaust_pressure * cylinder.rod_area
        - actuator.gas.atmospheric_pressure * cylinder.rod_cross_section - friction)
    assert retracting == pytest.approx(
        supply.supply_pressure * cylinder.rod_area - supply.exhaust_pressure * cylinder.cap_area
        + actuator.gas.atmospheric_pressure * cylinder.rod_cross_section - friction)
    assert retracting < extending  # the annulus is smaller than the piston


@pytest.mark.parametrize("force", [-90.0, -5.0, 0.0, 40.0, 120.0])
def test_least_supply_gives_exactly_the_force_asked(simulation, force):
    actuator = simulation.robot.actuators["beta"]
    pressure = least_supply_for_force(actuator, force)
    extending, retracting = stall_forces(actuator, pressure)
    assert (extending if force >= 0 else retracting) == pytest.approx(abs(force), abs=1e-9)


def test_demands_grow_with_the_weight_and_are_mirror_symmetric(simulation):
    heavy = _simulation('thorax.mass="3 kg"')
    four = np.ones(4, dtype=bool)
    light_demand = cylinder_demands(simulation, STANDING_ANGLES, four).reshape(4, 3)
    heavy_demand = cylinder_demands(heavy, STANDING_ANGLES, four).reshape(4, 3)
    # left and right legs of a level, symmetric stance need the same beta/gamma forces
    assert light_demand[0, 1:] == pytest.approx(light_demand[1, 1:], rel=0.05)
    assert np.all(np.abs(heavy_demand[:, 1:]) > np.abs(light_demand[:, 1:]))


def test_requirements_rank_standing_up_above_walking_above_standing(simulation):
    path = np.array([[0.0, math.radians(-65.0), math.radians(55.0)], STANDING_ANGLES])
    rising, standing, walking = supply_requirements(simulation, STANDING_ANGLES, path)
    assert rising.pressure > walking.pressure > standing.pressure  # 3 feet carry more
    # the default supply (50.3 psig) can stand up and walk
    assert simulation.supply_pressure() > rising.pressure
    check_supply(simulation, STANDING_ANGLES, walking=True)


def test_a_supply_below_what_statics_asks_is_refused_naming_the_situation():
    short = _simulation('actuators.supply_pressure="15 psig"')
    with pytest.raises(InsufficientSupplyError, match=r"15.0 psig .* standing"):
        check_supply(short, STANDING_ANGLES, walking=False)


def test_a_heavier_robot_needs_more_supply_to_rise(simulation):
    heavy = _simulation('thorax.mass="3 kg"')
    assert (rise_requirement(heavy, STANDING_ANGLES).pressure
            > rise_requirement(simulation, STANDING_ANGLES).pressure)


def test_stance_verdict_measures_height_joints_and_attitude(simulation):
    pose = np.tile(STANDING_ANGLES, 4)
    height = standing_height(simulation, STANDING_ANGLES)
    simulation.set_pose(pose, thorax_position=np.array([0.0, 0.0, height]))
    verdict = stance_verdict(simulation, STANDING_ANGLES)
    assert verdict["verified"], verdict["reasons"]
    assert verdict["target thorax height [m]"] == pytest.approx(height)

    bent = pose.copy()
    bent[4] += math.radians(10.0)  # front right beta
    simulation.set_pose(bent, thorax_position=np.array([0.0, 0.0, height - 0.06]))
    verdict = stance_verdict(simulation, STANDING_ANGLES)
    assert not verdict["verified"]
    assert verdict["joint with the largest error"] == "front_right_beta"
    assert verdict["largest joint error [deg]"] == pytest.approx(10.0, abs=1e-6)
    assert any("thorax at" in reason for reason in verdict["reasons"])

    tilt = math.radians(8.0)  # a rolled thorax (the nominal placement turned about x)
    simulation.set_pose(pose, thorax_position=np.array([0.0, 0.0, height]))
    nominal = simulation.data.qpos[3:7].copy()
    roll = np.array([math.cos(tilt / 2), math.sin(tilt / 2), 0.0, 0.0])
    quaternion = np.empty(4)
    mujoco.mju_mulQuat(quaternion, roll, nominal)
    simulation.set_pose(pose, thorax_position=np.array([0.0, 0.0, height]),
                        thorax_quaternion=quaternion)
    verdict = stance_verdict(simulation, STANDING_ANGLES)
    assert not verdict["verified"]
    assert max(abs(verdict["thorax roll [deg]"]), abs(verdict["thorax pitch [deg]"])) == (
        pytest.approx(8.0, abs=0.01))


def test_a_gate_ends_the_run_before_its_phase_and_the_summary_says_why(simulation, tmp_path):
    pose = np.tile(STANDING_ANGLES, 4)
    simulation.set_pose(pose, thorax_position=np.array(
        [0.0, 0.0, standing_height(simulation, STANDING_ANGLES)]))
    closed = np.ones(12, dtype=bool)
    phases = [Phase("first", 0.05, pose, closed),
              Phase("second", 0.05, pose, closed,
                    gate=lambda sim: ("not today", {"time [s]": sim.time})),
              Phase("third", 0.05, pose, closed)]
    run = run_phases(simulation, phases, tmp_path / "run", "gated")
    assert run.summary["stopped before"] == {"phase": "second", "reason": "not today"}
    assert list(run.summary["phases"]) == ["first"]
    assert run.summary["checks"]["second"]["time [s]"] == pytest.approx(0.05)
    assert run.recording["time [s]"][-1] == pytest.approx(0.05)
    assert (tmp_path / "run" / "recording.parquet").is_file()


def test_stand_up_checks_the_stance_after_the_hold(simulation):
    phases = stand_up_phases(simulation, posture=False)
    names = [phase.name for phase in phases]
    assert names == ["rest", "stand up", "hold", "stance check"]
    assert phases[-1].duration == 0.0 and phases[-1].gate is not None


def test_staged_rise_swings_front_feet_forward_and_rear_feet_back(simulation):
    phases = stand_up_phases(simulation, posture=False, staged=True)
    assert [phase.name for phase in phases] == [
        "rest", "swing out", "front pair up", "front pair back", "rear pair up",
        "step rear_left", "step rear_right", "hold",
        "stance check"]
    lying = simulation.joint_angles()
    signs = alpha_swing_signs(simulation, lying)
    swung = lying.copy()
    swung[0::3] += signs * STAGED_ALPHA
    simulation.set_pose(lying, thorax_position=np.array([0.0, 0.0, 1.0]))
    before = simulation.foot_positions()[:, 0]
    simulation.set_pose(swung, thorax_position=np.array([0.0, 0.0, 1.0]))
    after = simulation.foot_positions()[:, 0]
    front = np.array([leg.startswith("front") for leg in simulation.robot.legs])
    assert np.all(after[front] > before[front] + 0.1)
    assert np.all(after[~front] < before[~front] - 0.1)


def _stand(tmp_path, *overrides: str) -> dict:
    from pneumaquad.locomotion.capacity import rise_in_pairs

    simulation = _simulation(*overrides)
    staged = rise_in_pairs(simulation, STANDING_ANGLES)
    phases = stand_up_phases(simulation, posture=False, staged=staged)
    run = run_phases(simulation, phases, tmp_path / "stand", "stand")
    return {"staged": staged, **run.summary["checks"]["stance check"]}


@pytest.mark.slow
def test_stands_up_at_45_psig_by_rising_a_pair_at_a_time(tmp_path):
    verdict = _stand(tmp_path, 'actuators.supply_pressure="45 psig"')
    assert verdict["staged"]
    assert verdict["verified"], verdict["reasons"]


@pytest.mark.slow
def test_stands_up_with_a_3_kg_thorax(tmp_path):
    verdict = _stand(tmp_path, 'thorax.mass="3 kg"')
    assert verdict["staged"]
    assert verdict["verified"], verdict["reasons"]
