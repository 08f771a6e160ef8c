"""The simulated figures of docs/robot.md that no CLI command prints, measured on this code.

Each sub-command prints one group of figures (nothing is asserted; the tests hold the
bounds):

``stall``      blocked-piston force of each cylinder at full valve command (the ideal 50 psig
               supply through the underlapped valve), and what is left after the seal's
               breakaway force: the forces the standing figures are compared with
``coupling``   the front-right gamma 20° step (fixed thorax, all joints held) at a 1 ms
               control step against 0.1 ms and 0.5 ms, as tests/robot/test_robot_coupling.py;
               and how far the piston moves in one control step at the step's peak speed
``energy``     the exact-coupling checks of tests/robot/test_coupling_exact.py: a lossless
               air-spring robot's total energy over 10 s, closed chambers' P·V^n
``hold``       all 12 joints holding a mid-range posture for 60 s (fixed thorax): spread of
               the angles early and late, final error
``creep``      a vented front-right cylinder (no pneumatic force) under an external torque
               of 0.5 and 0.9 (below) and 1.1 and 2 (above) times its breakaway torque for
               1 s: joint travel with the shipped seal friction constraint, with 5 and 20
               no-slip iterations, and with MuJoCo's default (soft) friction constraint
``substeps``   ``pneumaquad leg validate --joint gamma --signal steps`` (fixed thorax, 16 s
               of steps) with 1, 2 and 10 Heun substeps, every control step recorded: the
               largest angle and chamber-pressure differences against 10
``gains``      ±25° steps of each front-right joint from the mid-range posture (fixed
               thorax, the other joints held): overshoot
``stance``     standing with a 2° leg-length error under position control and under force
               tracking; uneven shares without seal friction; a diagonal load shift asked
               of the robot standing still in the walking pose (seal friction on)
``feet``       the standing robot's foot contact forces against its weight
``crawl``      the 0.1 m crawl of tests/robot/test_walking.py: distance, drift, tip-over margin
``stand RUN``  from a ``pneumaquad robot stand`` run folder: thorax heights, body commands
               reached, cylinder forces as fractions of the ``stall`` forces, feet load
``walk RUN...`` from ``pneumaquad robot walk`` run folders: the judgement, yaw, air, speed,
               where the feet are on the ramp or the rough field
``profile``    where the wall time of ``pneumaquad robot walk --distance 1 --no-video`` goes:
               the compiled stepping chunks (timed) against the per-chunk Python feedback
``fk``         one leg's forward kinematics and Jacobian: compiled single-leg call against
               the batched NumPy path

Run: ``.venv/bin/python benchmarks/robot_figures.py SUB-COMMAND [RUN ...]``. Wall time on the
shared 2-core machine: ``substeps`` about 15 s, ``profile`` one 1 m walk (6-16 s), the others
a few seconds.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.io.run_folder import read_recording
from pneumaquad.locomotion.stance_control import StanceControlSettings, track_stance_loads
from pneumaquad.locomotion.walking import WALKING_ANGLES
from pneumaquad.params import load_actuator, load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.linkage import moment_arm
from pneumaquad.robot.scenarios import STANDING_ANGLES, leg_validation_phases, standing_height
from pneumaquad.robot.simulation import RobotSimulation

POSTURE_DEG = (0.0, -30.0, 60.0)
POSE = np.tile(np.radians(POSTURE_DEG), 4)
FRONT_RIGHT = (3, 4, 5)
JOINTS = ("alpha", "beta", "gamma")


def _simulation(*overrides: str, configuration: str = "fixed") -> RobotSimulation:
    return RobotSimulation(build_robot(load_robot("crr-quadruped", list(overrides)),
                                       configuration))


# --- stall ------------------------------------------------------------------------------
def stall_forces() -> dict[str, tuple[float, float, float]]:
    """Per joint type: (extending, retracting) blocked-piston force [N] at full command
    (10 V, 0 V) after 3 s from atmospheric chambers, and the seal breakaway force [N]."""
    result = {}
    for joint in JOINTS:
        actuator = load_actuator(f"crr-{joint}")
        params = pack_parameter_array([actuator])
        position = 0.5 * params[0]["stroke"]
        atmosphere = params[0]["atmospheric_pressure"]
        forces = []
        for voltage in (10.0, 0.0):
            state = np.array([initial_state(params[0], position, atmosphere, atmosphere)])
            supply = supply_state(actuator)
            out = new_outputs(1)
            for _ in range(3000):
                step_actuators(params, state, np.array([voltage]), np.array([position]),
                               np.zeros(1), 1e-3, 1, supply, out)
            forces.append(float(out[0]["pneumatic_force"]))
        result[joint] = (forces[0], -forces[1], actuator.friction.static_force)
    return result


def stall() -> None:
    for joint, (extend, retract, breakaway) in stall_forces().items():
        print(f"{joint}: blocked piston at full command {extend:.1f} N extending, "
              f"{retract:.1f} N retracting; minus the breakaway {breakaway:.1f} N: "
              f"{extend - breakaway:.1f} / {retract - breakaway:.1f} N")


# --- coupling ---------------------------------------------------------------------------
def gamma_step(*overrides: str, settle: float = 0.5, after: float = 0.6,
               record_period: float = 1e-3) -> dict[str, np.ndarray]:
    """Hold the posture ``settle`` s, then step front-right gamma by 20° for ``after`` s."""
    sim = _simulation(*overrides)
    sim.set_pose(POSE)
    sim.command_angles(POSE)
    sim.step(round(settle / sim.control_step))
    target = POSE.copy()
    target[5] += math.radians(20.0)
    sim.command_angles(target)
    per_record = round(record_period / sim.control_step)
    rows: dict[str, list] = {"time": [], "angles": [], "piston speed": []}
    for _ in range(round(after / record_period)):
        sim.step(per_record)
        rows["time"].append(sim.time)
        rows["angles"].append(np.degrees(sim.joint_angles()))
        rows["piston speed"].append(abs(float(sim.velocities[5])))
    return {name: np.array(values) for name, values in rows.items()}


def coupling() -> None:
    fine = gamma_step('simulation.control_step="0.1 ms"')
    coarse = gamma_step()
    half = gamma_step('simulation.control_step="0.5 ms"')
    for name, run in (("1 ms", coarse), ("0.5 ms", half)):
        error = np.abs(run["angles"] - fine["angles"])
        per_joint = error.max(axis=0)[list(FRONT_RIGHT)]
        print(f"{name} vs 0.1 ms: largest |Δθ| {error.max():.3f}° (front-right alpha, beta, "
              f"gamma {', '.join(f'{v:.3f}' for v in per_joint)}°), over the last 0.1 s "
              f"{error[-100:].max():.3f}°")
    speed = coarse["piston speed"].max()
    print(f"gamma piston: peak speed {speed:.3f} m/s, i.e. {speed * 1e-3 * 1e3:.3f} mm per "
          f"1 ms control step; final angle {coarse['angles'][-1, 5]:.2f}° (target 80°)")


# --- energy -----------------------------------------------------------------------------
def _released(gravity: bool, seal_friction: bool) -> RobotSimulation:
    """As tests/robot/test_coupling_exact.py: fixed thorax, every cylinder on a simple valve
    without leak (closed when uncommanded), both chambers at 3 bar, valves released."""
    robot = build_robot(load_robot("crr-quadruped"), "fixed")
    for joint_type, actuator in list(robot.actuators.items()):
        simple = actuator.valve.simple.model_copy(update={"leak_area": 0.0})
        update: dict[str, Any] = {"valve": actuator.valve.model_copy(
            update={"model": "simple", "simple": simple})}
        if not seal_friction:
            update["friction"] = actuator.friction.model_copy(
                update={"model": "viscous", "damping_coefficient": 0.0})
        robot.actuators[joint_type] = actuator.model_copy(update=update)
    if not gravity:
        robot.model.opt.gravity[:] = 0.0
    sim = RobotSimulation(robot)
    if not gravity:
        sim.model.opt.gravity[:] = 0.0
    sim.set_pose(POSE, chamber_pressure=3.0e5)
    sim.release()
    return sim


def _volumes(sim: RobotSimulation) -> tuple[np.ndarray, np.ndarray]:
    from pneumaquad.core.physics.chamber import chamber_volume_cap, chamber_volume_rod

    p, x = sim.params, sim.positions
    cap = np.array([chamber_volume_cap(x[i], p[i]["cap_area"], p[i]["cap_dead_length"])
                    for i in range(len(x))])
    rod = np.array([chamber_volume_rod(x[i], p[i]["stroke"], p[i]["rod_area"],
                                       p[i]["rod_dead_length"]) for i in range(len(x))])
    return cap, rod


def energy() -> None:
    sim = _released(gravity=False, seal_friction=False)
    p = sim.params
    n = p["heat_capacity_ratio"] * p["gas_constant"] / p["specific_heat_cp"] + 1.0
    rows = []
    for _ in range(1000):  # 10 s in 10 ms chunks
        sim.step(10)
        momentum = np.zeros(sim.model.nv)
        mujoco.mj_mulM(sim.model, sim.data, momentum, sim.data.qvel)
        kinetic = 0.5 * float(sim.data.qvel @ momentum)
        cap, rod = _volumes(sim)
        s = sim.state
        gas = (s["cap_pressure"] * cap + s["rod_pressure"] * rod) / (n - 1)
        atmosphere = p["atmospheric_pressure"] * (p["cap_area"] - p["rod_area"]) \
            * sim.positions
        rows.append((sim.time, kinetic, float(np.sum(gas + atmosphere))))
        if not np.isfinite(rows[-1][2]) or (len(rows) > 1 and rows[-1][0] < rows[-2][0]):
            break
    times, kinetic, stored = np.array(rows).T
    total = kinetic + stored
    deviation = np.abs(total - total[0])
    print(f"lossless air-spring robot (no gravity, no seal friction, closed valves), "
          f"{times[-1]:.2f} s: total energy {total[0]:.1f} J, largest deviation "
          f"{deviation.max() * 1e3:.2f} mJ ({deviation.max() / total[0]:.2g} of it); legs' "
          f"kinetic energy up to {kinetic.max():.3f} J; mean of the last second minus the "
          f"first {(total[-100:].mean() - total[:100].mean()) * 1e3:+.2f} mJ")
    sim = _released(gravity=True, seal_friction=True)
    dofs = sim.robot.dof_address

    def invariants() -> np.ndarray:
        cap, rod = _volumes(sim)
        s = sim.state
        return np.concatenate([s["cap_pressure"] * cap**n, s["rod_pressure"] * rod**n])

    start, initial = invariants(), sim.positions.copy()
    worst, travel = 0.0, 0.0
    for chunk in range(200):  # 2 s, ±4 N m square wave on every joint
        sim.data.qfrc_applied[dofs] = 4.0 if (chunk // 25) % 2 == 0 else -4.0
        sim.step(10)
        worst = max(worst, float(np.max(np.abs(invariants() / start - 1.0))))
        travel = max(travel, float(np.max(np.abs(sim.positions - initial))))
    print(f"closed chambers, gravity, seal friction, ±4 N m on every joint for 2 s: P·V^n "
          f"within {worst:.2g} of its start while the pistons move up to {travel * 1e3:.0f} mm")


# --- hold -------------------------------------------------------------------------------
def hold() -> None:
    sim = _simulation()
    sim.set_pose(POSE)
    sim.command_angles(POSE)
    times, angles = [], []
    for _ in range(6000):
        sim.step(10)
        times.append(sim.time)
        angles.append(np.degrees(sim.joint_angles()))
    times, angles = np.array(times), np.array(angles)
    for start, stop in ((2.0, 12.0), (10.0, 20.0), (50.0, 60.0)):
        inside = (times > start) & (times <= stop)
        spread = angles[inside].std(axis=0)
        print(f"std of the joint angles in {start:g}-{stop:g} s: largest {spread.max():.3g}° "
              f"({sim.robot.joint_names[int(spread.argmax())]})")
    error = angles[-1] - np.degrees(POSE)
    print(f"final error: largest {np.abs(error).max():.3f}° "
          f"({sim.robot.joint_names[int(np.abs(error).argmax())]}); "
          f"per joint type (alpha, beta, gamma): "
          f"{', '.join(f'{np.abs(error[k::3]).max():.3f}' for k in range(3))}°")


# --- creep ------------------------------------------------------------------------------
def vented_joint_travel(joint: str, load_ratio: float, *overrides: str,
                        soft: bool = False) -> float:
    """Joint travel [deg] in 1 s of a vented front-right cylinder under ``load_ratio``
    times its breakaway torque (as tests/robot/test_robot_coupling.py)."""
    sim = _simulation(*overrides)
    if soft:  # MuJoCo's default friction constraint (solref 0.02 s, solimp 0.9-0.95)
        sim.model.tendon_solref_fri[:] = (0.02, 1.0)
        sim.model.tendon_solimp_fri[:] = (0.9, 0.95, 0.001, 0.5, 2.0)
    sim.model.opt.gravity[:] = 0.0
    atmosphere = sim.params["atmospheric_pressure"]
    sim.params["supply_pressure"] = atmosphere
    sim.params["exhaust_pressure"] = atmosphere
    sim.set_pose(POSE, chamber_pressure=float(atmosphere[0]))
    sim.release()
    i = sim.robot.joint_names.index(f"front_right_{joint}")
    arm = abs(moment_arm(sim.robot.linkages[joint], POSE[i]))
    breakaway = sim.robot.actuators[joint].friction.static_force * arm
    sim.data.qfrc_applied[sim.robot.dof_address[i]] = load_ratio * breakaway
    sim.step(1)
    start = sim.joint_angles()[i]
    sim.step(round(1.0 / sim.control_step))
    return math.degrees(sim.joint_angles()[i] - start)


def creep() -> None:
    variants = (("shipped (no no-slip iterations)", (), False),
                ("5 no-slip iterations", ("simulation.noslip_iterations=5",), False),
                ("20 no-slip iterations", ("simulation.noslip_iterations=20",), False),
                ("MuJoCo's default soft friction", (), True))
    for ratios, label in (((0.5, 0.9), "below"), ((1.1, 2.0), "above")):
        for name, overrides, soft in variants:
            if label == "above" and soft:
                continue
            cells = []
            for ratio in ratios:
                travel = [vented_joint_travel(j, ratio, *overrides, soft=soft) for j in JOINTS]
                cells.append(f"{ratio:g} Fs: " + ", ".join(f"{t:.3g}" for t in travel))
            print(f"{label} breakaway, {name}: travel in 1 s [deg] (alpha, beta, gamma) "
                  + "; ".join(cells))


# --- substeps ---------------------------------------------------------------------------
def _step_train(substeps: int, folder: Path) -> dict[str, np.ndarray]:
    sim = _simulation(f"simulation.substeps={substeps}", "simulation.recording_every=1")
    phases = leg_validation_phases(sim, "gamma", "steps")
    return run_phases(sim, phases, folder / f"substeps-{substeps}", "gamma steps").recording


def substeps() -> None:
    with tempfile.TemporaryDirectory() as folder:
        runs = {n: _step_train(n, Path(folder)) for n in (1, 2, 10)}
    reference = runs[10]
    for n in (1, 2):
        run = runs[n]
        angle = {j: np.degrees(np.abs(run[f"front_right_{j} angle [rad]"]
                                      - reference[f"front_right_{j} angle [rad]"]).max())
                 for j in JOINTS}
        pressure = {j: max(np.abs(run[f"front_right_{j} {side} pressure [Pa]"]
                                  - reference[f"front_right_{j} {side} pressure [Pa]"]).max()
                           for side in ("cap", "rod")) / 1e3 for j in JOINTS}
        print(f"{n} vs 10 substeps over {reference['time [s]'][-1]:.0f} s: largest angle "
              f"difference " + ", ".join(f"{j} {angle[j]:.3g}°" for j in JOINTS)
              + "; chamber pressure " + ", ".join(f"{j} {pressure[j]:.3g} kPa" for j in JOINTS))


# --- gains ------------------------------------------------------------------------------
def gains() -> None:
    for k, joint in enumerate(JOINTS):
        cells = []
        for sign in (1.0, -1.0):
            sim = _simulation()
            sim.set_pose(POSE)
            sim.command_angles(POSE)
            sim.step(1000)
            target = POSE.copy()
            index = FRONT_RIGHT[k]
            target[index] += sign * math.radians(25.0)
            sim.command_angles(target)
            angles = []
            for _ in range(2000):
                sim.step(1)
                angles.append(sim.joint_angles()[index])
            angles = np.degrees(np.array(angles)) * sign
            goal = math.degrees(target[index]) * sign
            overshoot = max(0.0, angles.max() - goal) / 25.0 * 100.0
            cells.append(f"{sign * 25:+.0f}° step {overshoot:.0f} % overshoot "
                         f"(final error {abs(angles[-1] - goal):.2f}°)")
        print(f"{joint} (from {POSTURE_DEG[k]:g}°): " + "; ".join(cells))


# --- stance -----------------------------------------------------------------------------
def _stand_with_error(error_degrees: float, shares: np.ndarray | None, gain: float,
                      stiffness: float, seal_friction: bool = True,
                      angles: np.ndarray = STANDING_ANGLES):
    """As tests/robot/test_stance_tracking.py: stand, command front_left beta off by
    ``error_degrees`` for 3 s; returns (measured, desired) normal forces [N]."""
    sim = _simulation(configuration="quadruped")
    if not seal_friction:
        sim.seal["static_force"] = sim.seal["coulomb_force"] = 0.0
    pose = np.tile(angles, 4)
    height = standing_height(sim, angles) + 0.003
    sim.set_pose(pose, thorax_position=np.array([0.0, 0.0, height]))
    sim.command_angles(pose)
    sim.step(1000)
    reference = pose.copy()
    reference[sim.robot.joint_names.index("front_left_beta")] += math.radians(error_degrees)
    table = np.tile(reference, (10, 1))
    desired, late = None, []
    for chunk in range(300):
        if shares is not None:
            desired = track_stance_loads(sim, shares, force_gain=gain, stiffness=stiffness)
        sim.step(10, table, 0)
        if chunk >= 250:
            late.append(sim.foot_normal_forces())
    _stand_with_error.last_range = (np.min(late, axis=0), np.max(late, axis=0))
    return sim.foot_normal_forces(), desired


def stance() -> None:
    def fmt(values) -> str:
        return ", ".join(f"{v:.3g}" for v in values)

    default = StanceControlSettings()
    rigid, _ = _stand_with_error(2.0, None, 0.0, 1.0)
    print(f"standing pose, front_left beta 2° off, position control: feet (FL, FR, RL, RR) "
          f"{fmt(rigid)} N (sum {rigid.sum():.2f} N)")
    for gain, stiffness in ((0.01, 1.0), (default.force_gain, default.stiffness)):
        tracked, desired = _stand_with_error(2.0, np.ones(4), gain, stiffness)
        print(f"  force tracking k_F {gain:g} V/N, stiffness {stiffness:g}: {fmt(tracked)} N "
              f"for {fmt(desired)} N asked (largest difference "
              f"{np.abs(tracked - desired).max():.2f} N)")
    shares = np.array([1.0, 1.0, 1.0, 0.25])
    for seal in (False, True):
        for gain, stiffness in ((0.01, 1.0), (default.force_gain, default.stiffness)):
            tracked, desired = _stand_with_error(0.0, shares, gain, stiffness,
                                                 seal_friction=seal)
            print(f"standing pose, shares {fmt(shares)}, seal friction "
                  f"{'on' if seal else 'off'}, k_F {gain:g}, stiffness {stiffness:g}: "
                  f"{fmt(tracked)} N for {fmt(desired)} N asked (largest difference "
                  f"{np.abs(tracked - desired).max():.2f} N)")
    for seal in (True, False):
        tracked, desired = _stand_with_error(0.0, shares, default.force_gain,
                                             default.stiffness, seal_friction=seal,
                                             angles=WALKING_ANGLES)
        low, high = _stand_with_error.last_range
        print(f"walking pose, shares {fmt(shares)}, seal friction {'on' if seal else 'off'}, "
              f"defaults: {fmt(tracked)} N for {fmt(desired)} N asked (largest difference "
              f"{np.abs(tracked - desired).max():.2f} N); over the last 0.5 s each foot "
              f"between {fmt(low)} and {fmt(high)} N")


# --- feet, crawl ------------------------------------------------------------------------
def feet() -> None:
    from pneumaquad.console.app import initial_pose
    from pneumaquad.robot.feedback import foot_feedback

    sim = _simulation(configuration="quadruped")
    initial_pose(sim)  # settled for 1 s: the console's reset pose
    weight = mujoco.mj_getTotalmass(sim.model) * -sim.model.opt.gravity[2]
    total = foot_feedback(sim).contact.sum(axis=0)
    print(f"console reset pose after 1 s (tests/robot/test_feedback.py): feet contact z "
          f"{total[2]:.2f} N for a weight of {weight:.2f} N "
          f"({(total[2] / weight - 1) * 100:+.2f} %), net tangential "
          f"{np.hypot(total[0], total[1]):.3f} N")


def crawl() -> None:
    from pneumaquad.locomotion.walking import (
        WalkSettings,
        tip_over_series,
        walking_outcome,
        walking_phases,
    )

    sim = _simulation(configuration="quadruped")
    settings = WalkSettings(speed=0.03, period=4.0, distance=0.1)
    phases, plan = walking_phases(sim, settings)
    with tempfile.TemporaryDirectory() as folder:
        run = run_phases(sim, phases, Path(folder) / "walk", "walk 0.1 m")
    tip_over = tip_over_series(run.recording, run.summary, sim.robot, plan)
    outcome = walking_outcome(run.recording, run.summary, settings, sim.robot, tip_over)
    print(f"0.1 m crawl at 30 mm/s, 4 s cycle (tests/robot/test_walking.py): travelled "
          f"{outcome['distance travelled [m]']:.3f} m, drift {outcome['sideways drift [m]']:.3f} "
          f"m, tip-over margin < 0 {outcome['time with negative tip-over margin [%]']:.1f} %, "
          f"fell {outcome['fell']}; planned smallest margin {plan.margins.min() * 1000:.0f} mm")


# --- stand ------------------------------------------------------------------------------
def _phase_mask(recording, summary, name: str, skip: float = 0.0) -> np.ndarray:
    phase = summary["phases"][name]
    times = recording["time [s]"]
    return (times >= phase["start [s]"] + skip) & (
        times <= phase["start [s]"] + phase["duration [s]"])


def _weight(folder: Path) -> float:
    model = mujoco.MjModel.from_xml_path(str(folder / "model.xml"))
    return float(model.body_mass.sum() * -model.opt.gravity[2])


def stand(folder: Path) -> None:
    recording = read_recording(folder)
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    times, z = recording["time [s]"], recording["thorax z [m]"]
    start = summary["phases"]["stand up"]["start [s]"]
    rise = summary["phases"]["stand up"]["duration [s]"]
    tucked = np.argmin(np.abs(times - (start + 0.5 * rise)))
    hold = _phase_mask(recording, summary, "hold", skip=1.0)
    print(f"{folder}: thorax at rest {z[0]:.3f} m, feet tucked (mid-rise, "
          f"{times[tucked]:.1f} s) {z[tucked]:.3f} m, standing (hold) {z[hold].mean():.3f} m; "
          f"pitch in the hold {math.degrees(recording['thorax pitch [rad]'][hold].mean()):.1f}°")
    for name, column in (("height up", "thorax z [m]"), ("height down", "thorax z [m]"),
                         ("roll", "thorax roll [rad]"), ("pitch", "thorax pitch [rad]")):
        if name not in summary["phases"]:
            continue
        inside = _phase_mask(recording, summary, name)
        values = recording[column][inside]
        base = recording[column][hold].mean()
        change = values[-1] - base
        if column.endswith("[rad]"):
            print(f"  {name}: {math.degrees(change):+.1f}° at the end of the phase")
        else:
            print(f"  {name}: {change * 100:+.1f} cm at the end of the phase")
    legs = [c.removesuffix(" foot normal force [N]") for c in recording
            if c.endswith(" foot normal force [N]")]
    feet = sum(recording[f"{leg} foot normal force [N]"][hold] for leg in legs)
    print(f"  feet carry {feet.mean():.2f} N in the hold; weight {_weight(folder):.2f} N")
    available = {j: (e - s, r - s) for j, (e, r, s) in stall_forces().items()}
    rising = _phase_mask(recording, summary, "stand up")
    standing = _phase_mask(recording, summary, "hold", skip=2.0)  # its last second
    for joint in JOINTS:
        extend, retract = available[joint]
        columns = [c for c in recording if c.endswith(f"_{joint} force [N]")]
        forces = np.column_stack([recording[c] for c in columns])
        share = np.where(forces > 0, forces / extend, -forces / retract)
        peak = share[rising].max(axis=1)
        saturated = np.mean(peak > 0.95) * rise
        print(f"  {joint}: rising, largest force {np.abs(forces[rising]).max():.0f} N = "
              f"{peak.max() * 100:.0f} % of the stall force less breakaway (above 95 % for "
              f"{saturated:.1f} s of the {rise:g} s); standing (last second of the hold) "
              f"{np.abs(forces[standing]).mean(axis=0).min():.0f}-"
              f"{np.abs(forces[standing]).mean(axis=0).max():.0f} N = "
              f"{share[standing].mean(axis=0).max() * 100:.0f} % at most")


# --- walk -------------------------------------------------------------------------------
def walk(folder: Path) -> None:
    recording = read_recording(folder)
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    outcome = summary["walking"]
    environment = summary["environment"]
    inside = _phase_mask(recording, summary, "walk")
    walk_phase = summary["phases"]["walk"]
    yaw = np.degrees(recording["thorax yaw [rad]"][inside])
    print(f"{folder} ({environment}, {outcome['target distance [m]']:g} m): "
          f"{'success' if outcome['success'] else 'failure'} ({', '.join(outcome['reasons'])})")
    print(f"  travelled {outcome['distance travelled [m]']:.3f} m, drift "
          f"{outcome['sideways drift [m]']:.3f} m; loaded-feet margin < 0 "
          f"{outcome['time with negative static margin [%]']:.2f} % of the walk; tip-over "
          f"margin < 0 {outcome['time with negative tip-over margin [%]']:.2f} %, smallest "
          f"{outcome['smallest tip-over margin [m]'] * 1000:+.0f} mm; largest stance slide "
          f"{outcome['largest stance-foot slide [m]']:.3f} m; joints at a limit "
          f"{outcome['joints at a limit'] or 'none'}")
    print(f"  air {outcome['air per metre [NL/m]']:.2f} NL/m, "
          f"{walk_phase['mean air flow [NL/min]']:.2f} NL/min while walking (the tank lasts "
          f"{walk_phase['tank endurance at this flow [s]'] / 60:.0f} min); yaw while walking "
          f"{yaw.min():+.1f}° to {yaw.max():+.1f}°")
    print(f"  simulated {summary['simulated time [s]']:.1f} s in {summary['wall time [s]']:.1f} s "
          f"({summary['real-time factor']:.1f}x real time)")
    legs = [c.removesuffix(" foot x [m]") for c in recording if c.endswith(" foot x [m]")]
    parameters = load_robot("crr-quadruped").environment
    times = recording["time [s]"]
    if environment == "ramp":
        x0, slope = parameters.ramp_position[0], parameters.ramp_slope
        for leg in legs:
            x, z = recording[f"{leg} foot x [m]"], recording[f"{leg} foot z [m]"]
            loaded = recording[f"{leg} foot normal force [N]"] > 1.0
            on_plate = loaded & (x > x0) & (z > 0.01)
            first = times[np.argmax(on_plate)] if on_plate.any() else math.nan
            print(f"  {leg}: first loaded on the plate at {first:.1f} s; at the end x "
                  f"{x[-1]:.3f} m, {z[-1] * 1000:.0f} mm above the ground, "
                  f"{(x[-1] - x0) / math.cos(slope) * 1000:.0f} mm up the plate")
    if environment == "rough":
        x0, length = parameters.rough_position[0], parameters.rough_size[0]
        for leg in legs:
            x = recording[f"{leg} foot x [m]"]
            entered = times[np.argmax(x > x0)] if (x > x0).any() else math.nan
            left = times[np.argmax(x > x0 + length)] if (x > x0 + length).any() else math.nan
            print(f"  {leg}: into the field at {entered:.1f} s, beyond its far edge "
                  f"({x0 + length:g} m) at {left:.1f} s; at the end x {x[-1]:.3f} m")
    peaks = []
    for leg in legs:  # swings: unloaded stretches of the walk longer than 0.3 s
        free = inside & (recording[f"{leg} foot normal force [N]"] <= 1.0)
        z = recording[f"{leg} foot z [m]"]
        edges = np.flatnonzero(np.diff(np.concatenate([[0], free.astype(int), [0]])))
        for first, end in zip(edges[::2], edges[1::2], strict=True):
            if times[end - 1] - times[first] > 0.3:
                peaks.append(z[first:end].max() - z[first])
    if peaks:
        print(f"  swing foot lift above its lift-off point: median {np.median(peaks) * 1000:.0f} "
              f"mm, smallest {min(peaks) * 1000:.0f} mm, largest {max(peaks) * 1000:.0f} mm "
              f"({len(peaks)} swings; planned 40 mm)")
    thorax = recording["thorax x [m]"]
    marks = ", ".join(f"{t:g} s {thorax[np.argmin(np.abs(times - t))]:.2f} m"
                      for t in np.arange(20.0, times[-1], 20.0))
    print(f"  thorax x at {marks}")


# --- profile ----------------------------------------------------------------------------
def profile() -> None:
    from pneumaquad.locomotion.walking import WalkSettings, walking_phases

    _simulation(configuration="quadruped").step(1)  # compile (or load) the stepping loop
    sim = _simulation(configuration="quadruped")
    phases, _ = walking_phases(sim, WalkSettings(distance=1.0))
    inner = sim.step
    spent = [0.0, 0]

    def timed_step(*args: Any, **kwargs: Any) -> None:
        started = time.perf_counter()
        inner(*args, **kwargs)
        spent[0] += time.perf_counter() - started
        spent[1] += 1

    sim.step = timed_step  # this simulation only: the chunks the experiment runner calls
    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        run = run_phases(sim, phases, Path(folder) / "walk", "walk 1 m")
        wall = time.perf_counter() - started
    simulated = run.summary["simulated time [s]"]
    stepping = spent[0]
    print(f"flat 1 m walk: {simulated:.1f} s simulated in {wall:.1f} s ({simulated / wall:.1f}x "
          f"real time); {spent[1]} RobotSimulation.step chunks (MuJoCo, actuators, "
          f"controllers, compiled) {stepping:.1f} s = {stepping / wall * 100:.0f} %, the rest "
          f"(per-chunk feedback in Python: stance forces, swing and heading corrections; "
          f"recording) {100 - stepping / wall * 100:.0f} %")


# --- fk ---------------------------------------------------------------------------------
def fk() -> None:
    from pneumaquad.robot.kinematics import foot_jacobian, forward_kinematics_dh
    from pneumaquad.robot.legs import leg_dh_table

    robot = build_robot(load_robot("crr-quadruped"), "fixed")
    table = leg_dh_table(robot, "front_right")
    single = np.radians([0.0, -20.0, 80.0])
    batch = single[None, :]
    for name, angles in (("compiled single leg", single), ("batched NumPy (1, 3)", batch)):
        forward_kinematics_dh(table, angles)
        foot_jacobian(table, angles)
        count = 20000
        started = time.perf_counter()
        for _ in range(count):
            forward_kinematics_dh(table, angles)
            foot_jacobian(table, angles)
        per_call = (time.perf_counter() - started) / (2 * count) * 1e6
        print(f"{name}: {per_call:.1f} µs per call (FK or Jacobian)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("stall", "coupling", "hold", "creep", "substeps",
                                            "gains", "stance", "feet", "crawl", "energy",
                                            "stand",
                                            "walk", "profile", "fk"))
    parser.add_argument("runs", nargs="*", type=Path, help="run folders (stand, walk)")
    arguments = parser.parse_args()
    simple: dict[str, Any] = {"stall": stall, "coupling": coupling, "hold": hold,
                              "creep": creep, "substeps": substeps, "gains": gains,
                              "stance": stance, "feet": feet, "crawl": crawl, "energy": energy,
                              "profile": profile, "fk": fk}
    if arguments.command in simple:
        simple[arguments.command]()
        return
    if not arguments.runs:
        parser.error(f"{arguments.command} needs one or more run folders")
    for folder in arguments.runs:
        (stand if arguments.command == "stand" else walk)(folder)


if __name__ == "__main__":
    main()
