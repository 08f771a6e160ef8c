"""Tests of the coupled robot simulation: MuJoCo legs driven by the pneumatic kernel.

All runs use the ``fixed`` configuration (thorax held in space, as the thesis's single-leg
validation, 5.4) with the four legs in a mid-range posture and the front-right leg
commanded. They check physics rather than code paths: bit-reproducibility, the error of
the 1 ms coupling against a ten times finer step (and its first-order convergence), that a
closed-loop posture hold does not grow an oscillation, the air bookkeeping, and that the
seal friction in MuJoCo's constraint solver holds below the breakaway force and slips
above it.

The first stepping call compiles the stepping loop (a few seconds, once per process).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.linkage import moment_arm
from pneumaquad.robot.simulation import RobotSimulation

#: alpha, beta, gamma [deg] of every leg: mid-range, away from the end stops.
POSTURE_DEG = (0.0, -30.0, 60.0)
POSE = np.tile(np.radians(POSTURE_DEG), 4)
FRONT_RIGHT = np.array([3, 4, 5])
GAMMA_STEP_DEG = 20.0  # front-right gamma 60° -> 80°


def _simulation(*overrides: str) -> RobotSimulation:
    robot = build_robot(load_robot("crr-quadruped", list(overrides)), "fixed")
    return RobotSimulation(robot)


def _gamma_step(
    *overrides: str, settle: float = 0.5, after: float = 0.6, record_period: float = 1e-3
) -> dict[str, np.ndarray]:
    """Hold the posture for ``settle`` s, then step front-right gamma by 20° for ``after`` s.

    Recorded every ``record_period`` s from the step on: joint angles [deg], chamber
    pressures [Pa], air consumed [kg], time [s].
    """
    sim = _simulation(*overrides)
    sim.set_pose(POSE)
    sim.command_angles(POSE)
    sim.step(round(settle / sim.control_step))
    target = POSE.copy()
    target[5] += math.radians(GAMMA_STEP_DEG)
    sim.command_angles(target)
    per_record = round(record_period / sim.control_step)
    rows = {"time": [], "angles": [], "pressures": [], "air": [], "air_per_joint": []}
    for _ in range(round(after / record_period)):
        sim.step(per_record)
        rows["time"].append(sim.time)
        rows["angles"].append(np.degrees(sim.joint_angles()))
        rows["pressures"].append(sim.chamber_pressures())
        rows["air"].append(sim.air_consumed())
        rows["air_per_joint"].append(sim.air_consumed_per_joint())
    return {name: np.array(values) for name, values in rows.items()}


# --- 8. determinism ---------------------------------------------------------------------
def test_same_experiment_twice_is_bit_identical():
    first = _gamma_step(settle=0.1, after=0.2, record_period=0.01)
    second = _gamma_step(settle=0.1, after=0.2, record_period=0.01)
    for name in ("angles", "pressures", "air", "air_per_joint", "time"):
        assert np.array_equal(first[name], second[name]), name
    # and the experiment did something: the gamma joint moved and drew air
    assert np.ptp(first["angles"][:, 5]) > 5.0
    assert first["air"][-1] > 0.0


# --- 9. coupling error ------------------------------------------------------------------
def test_one_millisecond_coupling_agrees_with_a_ten_times_finer_step():
    """The 20° gamma step at 1 ms against 0.1 ms (controller, kernel and MuJoCo together).

    Measured (crr-quadruped as shipped, 2 Heun substeps; 5 substeps change these by
    < 1e-4°): max |Δθ| over the 0.6 s after the step 0.70° (gamma, during the rise;
    beta 0.37°, alpha 0.001°), max over the last 0.1 s 0.081°. The 0.5 ms run is off
    by 0.31° (0.25 ms: 0.11°): first order in the step, as expected of a zero-order-hold
    controller and valve command (error ≈ 0.78°/ms · (Δt − 0.1 ms)). Bounds: ~2× the
    measured values; the convergence ratio bound 0.6 against the first-order 0.44.
    """
    fine = _gamma_step('simulation.control_step="0.1 ms"')
    coarse = _gamma_step()
    half = _gamma_step('simulation.control_step="0.5 ms"')
    assert np.allclose(fine["time"], coarse["time"]) and np.allclose(half["time"], fine["time"])
    error = np.abs(coarse["angles"] - fine["angles"])
    error_half = np.abs(half["angles"] - fine["angles"])
    transient = error.max()
    end = error[-100:].max()
    # Measured 1.62° with the seal friction stuck by MuJoCo's dry-friction constraint
    # (0.70° with soft friction): stick/slip instants shift by a step.
    assert transient < 2.5, f"max angle difference {transient:.3f}° (measured 1.62°)"
    # Measured 0.45°: where a joint comes to rest inside the stiction dead band differs
    # between the two steps (0.081° with soft seal friction).
    assert end < 1.0, f"final angle difference {end:.3f}° (measured 0.45°)"
    # With sticking seal friction the error falls more slowly than first order in the step
    # (measured 1.27° at 0.5 ms vs 1.62° at 1 ms): stick/slip instants quantise to the step.
    assert error_half.max() < 0.9 * transient, (error_half.max(), transient)
    # both reach the commanded angle (the step happened, and the same way)
    target = POSTURE_DEG[2] + GAMMA_STEP_DEG
    for run in (fine, coarse):
        assert abs(run["angles"][-1, 5] - target) < 1.5
        assert run["angles"][:, 5].max() > target - 1.0


# --- 10, 11. holding a posture: stability and air ---------------------------------------
HOLD_SECONDS = 60.0


@pytest.fixture(scope="module")
def holding() -> dict[str, np.ndarray]:
    """All 12 joints closed-loop holding the posture for 60 s, recorded at 100 Hz.

    About 2 s of wall time (60 000 control steps).
    """
    sim = _simulation()
    sim.set_pose(POSE)
    sim.command_angles(POSE)
    per_record = round(0.01 / sim.control_step)
    rows = {"time": [], "angles": [], "air": [], "air_per_joint": []}
    for _ in range(round(HOLD_SECONDS / 0.01)):
        sim.step(per_record)
        rows["time"].append(sim.time)
        rows["angles"].append(np.degrees(sim.joint_angles()))
        rows["air"].append(sim.air_consumed())
        rows["air_per_joint"].append(sim.air_consumed_per_joint())
    return {name: np.array(values) for name, values in rows.items()}


def _window(run, start, stop):
    return (run["time"] > start) & (run["time"] <= stop)


def test_posture_hold_does_not_grow_an_oscillation(holding):
    """Measured std of the joint angles (largest joint): 0.169° in 2-12 s (alpha settling
    from the initial pressure imbalance; beta 0.080°, gamma 0.040°), 0.016° in 10-20 s and
    4.5e-9° in 50-60 s (every joint stuck at its reference by the seal friction, the
    chambers at rest: the underlapped valve of eq 4.2.7 feeds each port from one source
    pressure, so the flows die out). Mean angle error in the last 10 s: 5e-9°.
    """
    early = holding["angles"][_window(holding, 2.0, 12.0)]
    late = holding["angles"][_window(holding, HOLD_SECONDS - 10.0, HOLD_SECONDS)]
    assert np.all(np.isfinite(holding["angles"]))
    early_std, late_std = early.std(axis=0), late.std(axis=0)
    assert np.all(late_std <= early_std + 1e-9), (early_std, late_std)
    assert late_std.max() < 0.05  # and small in absolute terms
    error = late.mean(axis=0) - np.degrees(POSE)
    assert np.max(np.abs(error)) < 1.0, error
    # the integral action removes the error: the end is within 0.05° of the reference
    # Dry seal friction holds a joint as soon as the cylinder force left over is below
    # breakaway: measured 0.12° final error on the beta joints (a stiction dead band).
    assert np.max(np.abs(holding["angles"][-1] - np.degrees(POSE))) < 0.5


def test_air_bookkeeping_while_holding(holding):
    total, per_joint = holding["air"], holding["air_per_joint"]
    assert np.allclose(total, per_joint.sum(axis=1), rtol=1e-12, atol=1e-18)
    assert total[-1] > 0.0
    assert np.all(np.diff(total) >= 0.0)  # drawn mass never decreases
    assert np.all(np.diff(per_joint, axis=0) >= 0.0)
    assert np.all(per_joint[-1] >= 0.0)
    assert per_joint[-1].max() > 0.0  # the joints that moved drew air
    # the four legs are the same robot in the same posture: they draw the same air
    legs = per_joint[-1].reshape(4, 3)
    # Left and right alphas stick at slightly different instants (mirrored frames): their
    # air differs by about 2e-6 kg of 1e-5 kg.
    assert np.allclose(legs, legs[0], rtol=1e-3, atol=5e-6)


def test_stepping_joint_draws_more_air_than_the_held_ones():
    run = _gamma_step(settle=0.2, after=0.4, record_period=0.01)
    drawn = run["air_per_joint"][-1] - run["air_per_joint"][0]
    assert np.allclose(run["air"], run["air_per_joint"].sum(axis=1), rtol=1e-12, atol=1e-18)
    front_right_gamma = drawn[5]
    others = np.delete(drawn, 5)
    assert front_right_gamma > 10 * others.max()


# --- 12. seal friction in MuJoCo --------------------------------------------------------
NOSLIP = "simulation.noslip_iterations=20"


def _vented_joint_motion(joint: str, load_ratio: float, *overrides: str) -> tuple[float, float]:
    """Joint travel [deg] over 1 s under an external torque of ``load_ratio``·Fs·|r|, and
    the largest pneumatic force at the end as a fraction of Fs.

    Zero gravity, valves uncommanded and vented: supply and exhaust at atmospheric
    pressure and both chambers starting there, so the pneumatic force is zero and only
    the seal friction (MuJoCo ``frictionloss`` on the cylinder tendon, Fs at rest) holds
    the joint against the torque applied through ``qfrc_applied``.
    """
    sim = _simulation(*overrides)
    sim.model.opt.gravity[:] = 0.0
    atmosphere = sim.params["atmospheric_pressure"]
    sim.params["supply_pressure"] = atmosphere
    sim.params["exhaust_pressure"] = atmosphere
    sim.set_pose(POSE, chamber_pressure=float(atmosphere[0]))
    sim.release()
    i = sim.robot.joint_names.index(f"front_right_{joint}")
    actuator = sim.robot.actuators[joint]
    arm = abs(moment_arm(sim.robot.linkages[joint], POSE[i]))
    breakaway_torque = actuator.friction.static_force * arm
    sim.data.qfrc_applied[sim.robot.dof_address[i]] = load_ratio * breakaway_torque
    sim.step(1)
    start = sim.joint_angles()[i]
    sim.step(round(1.0 / sim.control_step))
    pneumatic = np.max(np.abs(sim.cylinder_forces())) / actuator.friction.static_force
    return math.degrees(sim.joint_angles()[i] - start), pneumatic


@pytest.mark.parametrize("joint", ["alpha", "beta", "gamma"])
@pytest.mark.parametrize("load_ratio", [0.5, 0.9])
def test_seal_friction_holds_below_breakaway(joint, load_ratio):
    """Measured travel over 1 s with 20 noslip iterations: beta 0.0011°, alpha and gamma
    < 1e-6°."""
    travel, pneumatic = _vented_joint_motion(joint, load_ratio, NOSLIP)
    assert abs(travel) < 0.01, travel
    assert pneumatic < 1e-3  # a stuck piston leaves the vented chambers at atmosphere


@pytest.mark.parametrize("joint", ["alpha", "beta", "gamma"])
@pytest.mark.parametrize("load_ratio", [1.1, 2.0])
def test_seal_friction_slips_above_breakaway(joint, load_ratio):
    """Measured travel over 1 s: 5.5-8° at 1.1 Fs, 16-24° at 2 Fs (in the torque's sense)."""
    travel, _ = _vented_joint_motion(joint, load_ratio, NOSLIP)
    assert travel > 1.0, travel


@pytest.mark.parametrize("joint", ["beta"])
def test_seal_friction_holds_with_the_shipped_solver_settings(joint):
    """Without no-slip iterations the stiff friction constraint alone holds the joint to a
    slow creep: measured 0.007-0.063° in 1 s at 0.5 Fs (0.7-4.6° with MuJoCo's default
    soft friction), which does not run away into a slip."""
    travel, _ = _vented_joint_motion(joint, 0.5)
    assert abs(travel) < 0.15, travel
