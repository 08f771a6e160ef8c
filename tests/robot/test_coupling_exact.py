"""The actuator-MuJoCo coupling is exact in what it exchanges: energy and chamber volumes.

All runs hold the thorax fixed (``fixed`` configuration). With closed valves (simple
valve, no leak, uncommanded) every chamber is a closed adiabatic gas spring, so:

* a closed chamber keeps P·V^n whatever the piston does, n = k·R/cp + 1 the compression
  exponent of the thesis's energy balance (eq 4.1.10; 1.397 with the thesis's cp);
* with gravity off and no seal friction nothing dissipates, so the total energy — the
  legs' kinetic energy, the gas's internal energy P·V/(n − 1) of every chamber and the
  potential Patm·(A_cap − A_rod)·x of the atmosphere pushing on the rod side — is
  conserved;
* the piston position the kernel integrates to is the linkage position of the present
  joint angle (eq 5.2.1-5.2.6).

Sampling the pistons one step late (the coupling before the fix) made the lossless robot
gain energy until it diverged at 0.55 s and let P·V^n wander by ±0.3 %.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from pneumaquad.core.layout import float_view
from pneumaquad.core.physics.chamber import chamber_volume_cap, chamber_volume_rod
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import RobotModel, build_robot
from pneumaquad.robot.coupling import piston_from_angle
from pneumaquad.robot.feedback import tibia_body_legs
from pneumaquad.robot.simulation import RobotSimulation

POSE = np.tile(np.radians((0.0, -30.0, 60.0)), 4)
CHAMBER_PRESSURE = 3.0e5  # [Pa] absolute, both chambers of every cylinder
CHUNK = 10  # control steps between samples


def _closed_valves(robot: RobotModel, seal_friction: bool) -> RobotModel:
    """Every cylinder on a simple valve without leak (closed when uncommanded); seal
    friction as shipped or none (viscous model with zero damping)."""
    for joint_type, actuator in list(robot.actuators.items()):
        simple = actuator.valve.simple.model_copy(update={"leak_area": 0.0})
        valve = actuator.valve.model_copy(update={"model": "simple", "simple": simple})
        update = {"valve": valve}
        if not seal_friction:
            update["friction"] = actuator.friction.model_copy(
                update={"model": "viscous", "damping_coefficient": 0.0})
        robot.actuators[joint_type] = actuator.model_copy(update=update)
    return robot


def _released(gravity: bool, seal_friction: bool) -> RobotSimulation:
    robot = _closed_valves(build_robot(load_robot("crr-quadruped"), "fixed"), seal_friction)
    if not gravity:
        robot.model.opt.gravity[:] = 0.0
    simulation = RobotSimulation(robot)
    simulation.set_pose(POSE, chamber_pressure=CHAMBER_PRESSURE)
    simulation.release()  # valves at their offset: closed
    return simulation


def _compression_exponent(simulation: RobotSimulation) -> np.ndarray:
    """n = k·R/cp + 1 per cylinder (eq 4.1.10, adiabatic)."""
    p = simulation.params
    return p["heat_capacity_ratio"] * p["gas_constant"] / p["specific_heat_cp"] + 1.0


def _volumes(simulation: RobotSimulation) -> tuple[np.ndarray, np.ndarray]:
    p, x = simulation.params, simulation.positions
    cap = np.array([chamber_volume_cap(x[i], p[i]["cap_area"], p[i]["cap_dead_length"])
                    for i in range(len(x))])
    rod = np.array([chamber_volume_rod(x[i], p[i]["stroke"], p[i]["rod_area"],
                                       p[i]["rod_dead_length"]) for i in range(len(x))])
    return cap, rod


def _energies(simulation: RobotSimulation) -> tuple[float, float]:
    """(kinetic, gas + atmosphere) energy [J] of the present state."""
    model, data = simulation.model, simulation.data
    momentum = np.zeros(model.nv)
    mujoco.mj_mulM(model, data, momentum, data.qvel)  # the state's own mass matrix
    kinetic = 0.5 * float(data.qvel @ momentum)
    p, s = simulation.params, simulation.state
    cap, rod = _volumes(simulation)
    n = _compression_exponent(simulation)
    gas = (s["cap_pressure"] * cap + s["rod_pressure"] * rod) / (n - 1.0)
    atmosphere = p["atmospheric_pressure"] * (p["cap_area"] - p["rod_area"]) * simulation.positions
    return kinetic, float(np.sum(gas + atmosphere))


def test_lossless_air_spring_robot_keeps_its_energy() -> None:
    simulation = _released(gravity=False, seal_friction=False)
    seconds = 10.0
    rows = []
    for _ in range(round(seconds / (CHUNK * simulation.control_step))):
        simulation.step(CHUNK)
        rows.append(_energies(simulation))
    kinetic, stored = np.array(rows).T
    total = kinetic + stored
    start = total[0]
    # the legs swing on their air springs the whole time (nothing damps them)
    assert kinetic[-100:].max() > 0.3 * kinetic.max() > 0.0
    # within 2 % of the start (measured: 1.8e-5, i.e. 8 mJ of 434 J)
    assert np.max(np.abs(total - start)) < 0.02 * start
    # and tighter, against the energy that sloshes between legs and gas (KE up to 0.12 J):
    # symplectic Euler's bounded oscillation (measured 6 % of it), no growth
    assert np.max(np.abs(total - start)) < 0.15 * kinetic.max()
    # no trend: the first and the last second agree (measured within 0.5 mJ)
    per_second = round(1.0 / (CHUNK * simulation.control_step))
    drift = abs(total[-per_second:].mean() - total[:per_second].mean())
    assert drift < 0.02 * kinetic.max()


def test_closed_chambers_keep_p_v_to_the_n_in_the_coupled_robot() -> None:
    # gravity, the shipped seal friction, and a ±4 N m square wave of external torque on
    # every joint (period 0.5 s) that swings the legs on their air springs
    simulation = _released(gravity=True, seal_friction=True)
    n = _compression_exponent(simulation)
    dofs = simulation.robot.dof_address

    def invariants() -> np.ndarray:
        cap, rod = _volumes(simulation)
        s = simulation.state
        return np.concatenate([s["cap_pressure"] * cap**n, s["rod_pressure"] * rod**n])

    start = invariants()
    travel, worst = 0.0, 0.0
    initial_positions = simulation.positions.copy()
    for chunk in range(round(2.0 / (CHUNK * simulation.control_step))):
        simulation.data.qfrc_applied[dofs] = 4.0 if (chunk // 25) % 2 == 0 else -4.0
        simulation.step(CHUNK)
        worst = max(worst, float(np.max(np.abs(invariants() / start - 1.0))))
        travel = max(travel, float(np.max(np.abs(simulation.positions - initial_positions))))
    assert travel > 0.005  # the pistons moved by more than 5 mm
    assert worst < 1e-3  # measured 1.5e-4 (Heun with one substep; 0.2 % with k for n)


def test_kernel_piston_is_the_linkage_position_of_the_present_joint_angle() -> None:
    robot = build_robot(load_robot("crr-quadruped"), "fixed")
    simulation = RobotSimulation(robot)
    simulation.set_pose(POSE)
    target = POSE.copy()
    target[5] += np.radians(20.0)  # front-right gamma step while all joints are controlled
    simulation.command_angles(target)
    moved = 0.0
    for _ in range(30):
        simulation.step(CHUNK)
        angles = simulation.joint_angles()
        linkage = np.array([piston_from_angle(simulation.linkage[i], angles[i])
                            for i in range(robot.joint_count)])
        np.testing.assert_allclose(simulation.positions, linkage, rtol=0.0, atol=1e-9)
        np.testing.assert_allclose(simulation.state["position"], linkage, rtol=0.0,
                                   atol=1e-9)
        moved = max(moved, abs(float(simulation.velocities[5])))
    assert moved > 0.01  # [m/s]: sampled while the piston moves


@pytest.mark.parametrize("chunk", [1, 7])
def test_chunk_size_does_not_change_the_run(chunk: int) -> None:
    """Between chunks the state is brought to the present and picked up again unchanged:
    stepping in chunks of 1 or 7 gives the run of one 70-step chunk bit for bit."""

    def run(size: int) -> np.ndarray:
        simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
        simulation.set_pose(POSE)
        target = POSE.copy()
        target[5] += np.radians(20.0)
        simulation.command_angles(target)
        for _ in range(70 // size):
            simulation.step(size)
        return np.concatenate([simulation.data.qpos, float_view(simulation.state).ravel()])

    np.testing.assert_array_equal(run(chunk), run(70))


def test_recording_columns_hold_what_their_names_say() -> None:
    """Each recorded piston column is the linkage position of its own angle column: a
    swap of same-shaped arrays (positions and references, say) between the simulation
    and the compiled step or the recording shows here."""
    from pneumaquad.robot.recording import recording_columns, recording_row

    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
    simulation.set_pose(POSE)
    target = POSE.copy()
    target[5] += np.radians(20.0)
    simulation.command_angles(target)
    columns = recording_columns(simulation)
    rows = []
    for _ in range(20):
        simulation.step(CHUNK)
        rows.append(recording_row(simulation, simulation.reference_angles))
    recording = dict(zip(columns, np.array(rows).T, strict=True))
    for i, joint in enumerate(simulation.robot.joint_names):
        linkage = simulation.linkage[i]
        stroke = simulation.params[i]["stroke"]
        angle, reference = recording[f"{joint} angle [rad]"], recording[f"{joint} reference [rad]"]
        position = [piston_from_angle(linkage, value) for value in angle]
        wanted = [min(max(piston_from_angle(linkage, value), 0.0), stroke) for value in reference]
        np.testing.assert_allclose(recording[f"{joint} piston position [m]"], position,
                                   rtol=0.0, atol=1e-9)
        np.testing.assert_allclose(recording[f"{joint} piston reference [m]"], wanted,
                                   rtol=0.0, atol=1e-12)
    gamma = recording["front_right_gamma piston position [m]"]
    assert np.ptp(gamma) > 0.005  # the step moved the piston: position and reference differ


def test_simulations_of_one_robot_model_do_not_interfere() -> None:
    """Two simulations built from one RobotModel, stepped in turn, each give the run a
    simulation of its own gives: the seal friction each writes per step (here the
    actuator's friction law, whose slope goes into the tendon damping) goes to its own
    copy of the MuJoCo model."""
    actuator_friction = 'simulation.seal_friction="actuator"'

    def gamma_step(simulation: RobotSimulation, degrees: float) -> None:
        simulation.set_pose(POSE)
        target = POSE.copy()
        target[5] += np.radians(degrees)
        simulation.command_angles(target)

    robot = build_robot(load_robot("crr-quadruped", [actuator_friction]), "fixed")
    first, second = RobotSimulation(robot), RobotSimulation(robot)
    gamma_step(first, 20.0)
    gamma_step(second, -15.0)
    for _ in range(30):
        first.step(CHUNK)
        second.step(CHUNK)
    alone = RobotSimulation(build_robot(load_robot("crr-quadruped", [actuator_friction]),
                                        "fixed"))
    gamma_step(alone, 20.0)
    alone.step(30 * CHUNK)
    np.testing.assert_array_equal(first.data.qpos, alone.data.qpos)
    np.testing.assert_array_equal(first.state, alone.state)


def _standing_quadruped() -> RobotSimulation:
    from pneumaquad.console.app import initial_pose

    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped"))
    initial_pose(simulation)  # dropped onto its feet from 3 mm, closed loop
    return simulation


def test_contact_forces_between_chunks_are_those_of_the_present_contacts() -> None:
    """Between chunks the foot forces equal MuJoCo's own forward dynamics of the state
    (mj_step1 alone would leave the last step's constraint solution under the new
    contact rows: feet read 0 N at times while the robot stood on them)."""
    simulation = _standing_quadruped()
    for _ in range(60):
        simulation.step(7)  # chunks that end between the 10 ms recording grid
        check = mujoco.MjData(simulation.model)
        mujoco.mj_copyData(check, simulation.model, simulation.data)
        mujoco.mj_forward(simulation.model, check)
        forces = simulation.foot_normal_forces()
        model, data = simulation.model, check
        expected = np.zeros(4)
        wrench = np.zeros(6)
        tibia = tibia_body_legs(simulation.robot)
        for index in range(data.ncon):
            contact = data.contact[index]
            for body in (model.geom_bodyid[contact.geom1], model.geom_bodyid[contact.geom2]):
                if int(body) in tibia:
                    mujoco.mj_contactForce(model, data, index, wrench)
                    expected[tibia[int(body)]] += abs(wrench[0])
        np.testing.assert_allclose(forces, expected, rtol=1e-6, atol=1e-6)
    weight = simulation.model.body_mass.sum() * 9.81
    assert simulation.foot_normal_forces().sum() == pytest.approx(weight, rel=0.05)


def test_chunk_size_does_not_change_a_run_with_contacts() -> None:
    def run(size: int) -> np.ndarray:
        simulation = _standing_quadruped()
        for _ in range(140 // size):
            simulation.step(size)
        return np.concatenate([simulation.data.qpos, float_view(simulation.state).ravel()])

    np.testing.assert_array_equal(run(1), run(140))
    np.testing.assert_array_equal(run(7), run(140))
