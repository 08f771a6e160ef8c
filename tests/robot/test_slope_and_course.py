"""Slope-aware body placement, the hill, course hold and the turn leak: closed forms and
the sign of each correction on the standing robot (the walks are in
test_walking_terrain.py, slow)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from pneumaquad.locomotion.body_placement import ground_plane, uphill_offset
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot


@pytest.mark.parametrize("slope_deg", [0.0, 8.0, 12.0, 30.0])
@pytest.mark.parametrize("azimuth_deg", [0.0, 90.0, 200.0])
def test_ground_plane_recovers_a_tilted_plane(slope_deg: float, azimuth_deg: float) -> None:
    """Four (or three) points of the plane z = tan θ·(x cos φ + y sin φ) + 0.1: the fitted
    normal is (−tan θ cos φ, −tan θ sin φ, 1) normalised."""
    slope, azimuth = math.radians(slope_deg), math.radians(azimuth_deg)
    xy = np.array([[0.35, 0.38], [0.36, -0.39], [-0.37, 0.4], [-0.35, -0.36]])
    z = math.tan(slope) * (xy[:, 0] * math.cos(azimuth) + xy[:, 1] * math.sin(azimuth)) + 0.1
    feet = np.column_stack([xy, z])
    expected = np.array([-math.tan(slope) * math.cos(azimuth),
                         -math.tan(slope) * math.sin(azimuth), 1.0])
    expected /= np.linalg.norm(expected)
    for chosen in (feet, feet[:3]):
        normal = ground_plane(chosen)
        assert normal is not None
        assert np.allclose(normal, expected, atol=1e-12)


def test_ground_plane_of_collinear_feet_is_none() -> None:
    feet = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.1], [1.0, 0.0, 0.2]])
    assert ground_plane(feet) is None
    assert ground_plane(feet[:2]) is None


@pytest.mark.parametrize("slope_deg", [0.0, 5.0, 12.0, 25.0])
def test_uphill_offset_puts_the_centre_of_mass_back_over_its_foot(slope_deg: float) -> None:
    """A centre of mass h above a plane rising in +x: after the offset its vertical meets
    the plane at the foot of its normal (as on level ground); the offset lies in the
    plane, points uphill and is h·tan θ long."""
    slope, height = math.radians(slope_deg), 0.38
    normal = np.array([-math.sin(slope), 0.0, math.cos(slope)])
    foot = np.array([0.2, 0.1, 0.2 * math.tan(slope)])  # a point of the plane z = x tan θ
    offset = uphill_offset(normal, height)
    centre = foot + height * normal + offset
    down = (centre - foot) @ normal / normal[2]  # along -z to the plane
    meets = centre - np.array([0.0, 0.0, down])
    assert np.allclose(meets, foot, atol=1e-12)
    assert abs(offset @ normal) < 1e-12
    assert offset[0] >= 0.0 and abs(offset[1]) < 1e-15
    assert np.linalg.norm(offset) == pytest.approx(height * math.tan(slope), abs=1e-12)


def test_the_hill_climbs_to_a_flat_top_and_comes_down_again() -> None:
    """The hill: the ramp plate, a top level with its upper edge and the plate mirrored
    about the top's middle (its upper edge on the top's far end, its lower on the
    ground)."""
    parameters = load_robot("crr-quadruped", ['environment.ramp_slope="12 deg"'])
    robot = build_robot(parameters, "quadruped", environment="hill")
    model = robot.model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    environment = parameters.environment
    slope, (length, _, thickness) = environment.ramp_slope, environment.ramp_size
    lower_edge = environment.ramp_position[0]
    top_height = length * math.sin(slope) + thickness * math.cos(slope)
    top_start = lower_edge + length * math.cos(slope) - thickness * math.sin(slope)

    def box_top(name: str) -> np.ndarray:
        """Corners of the upper face of a box geom [m]: (4, 3)."""
        geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
        half = model.geom_size[geom]
        rotation = data.geom_xmat[geom].reshape(3, 3)
        corners = [data.geom_xpos[geom] + rotation @ (half * np.array([sx, sy, 1.0]))
                   for sx in (-1, 1) for sy in (-1, 1)]
        return np.array(corners)

    top = box_top("hill_top")
    assert np.allclose(top[:, 2], top_height, atol=1e-12)
    assert top[:, 0].min() == pytest.approx(top_start, abs=1e-12)
    assert top[:, 0].max() == pytest.approx(top_start + environment.hill_top_length, abs=1e-12)
    ramp, descent = box_top("ramp"), box_top("descent")
    assert ramp[:, 2].max() == pytest.approx(top_height, abs=1e-12)
    assert descent[:, 2].max() == pytest.approx(top_height, abs=1e-12)
    middle = top_start + environment.hill_top_length / 2
    assert np.allclose(np.sort(2 * middle - ramp[:, 0]), np.sort(descent[:, 0]), atol=1e-12)


def _standing_simulation():
    from pneumaquad.console.app import initial_pose
    from pneumaquad.robot.simulation import RobotSimulation

    sim = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped"))
    standing = initial_pose(sim)
    sim.step(1000)
    return sim, standing


def test_course_hold_steers_back_towards_the_line() -> None:
    """A body found left of its line (cross-track > 0) is given a heading turned
    clockwise, towards the line, by course_gain per metre; the bias is limited."""
    from pneumaquad.locomotion.heading_control import HeadingHold
    from pneumaquad.locomotion.walk import robot_gait

    sim, standing = _standing_simulation()
    gait = robot_gait(sim.robot, speed=0.02, heading=0.0, duty_factor=0.9, period=8.0,
                      step_height=0.04, angles=np.radians([0.0, -20.0, 80.0]),
                      minimum_margin=0.06, lift_fraction=0.25, transfer_gap=0.04,
                      start_up=True)
    from pneumaquad.locomotion.course_kernels import gait_track

    hold = HeadingHold(sim, lambda times: np.tile(standing, (len(times), 1)),
                       track=gait_track(gait, sim.time, 8.0), course_gain=1.5,
                       course_limit=math.radians(8.0))
    chunk = sim.time + sim.control_step * np.arange(1, 11)
    hold(chunk)
    start = hold.heading
    assert hold.cross_track == pytest.approx(0.0, abs=1e-12)  # the line starts here
    thorax = sim.robot.thorax_id
    for lateral, expected in ((0.02, -0.03), (-0.04, 0.06), (0.5, -math.radians(8.0))):
        shift = np.zeros(3)
        shift[1] = lateral
        sim.data.xpos[thorax] += shift  # where the call reads the thorax from
        hold(chunk)
        sim.data.xpos[thorax] -= shift
        assert hold.cross_track == pytest.approx(lateral, abs=2e-3)
        assert hold.heading - start == pytest.approx(expected, abs=0.004)


def test_a_lasting_rotation_leaks_into_a_turn_of_the_stance_feet() -> None:
    """With the feet rotation c held, each foot turns by −turn_leak·c times the change of
    its stance travel: a stance foot, whose travel falls, turns by +leak·c·Δ (clockwise
    for c < 0 ... counter-clockwise body), a swinging one the other way."""
    from pneumaquad.gait.crawl import stance_travel
    from pneumaquad.locomotion.heading_control import HeadingHold
    from pneumaquad.locomotion.walk import robot_gait

    sim, standing = _standing_simulation()
    gait = robot_gait(sim.robot, speed=0.02, heading=0.0, duty_factor=0.9, period=8.0,
                      step_height=0.04, angles=np.radians([0.0, -20.0, 80.0]),
                      minimum_margin=0.06, lift_fraction=0.25, transfer_gap=0.04,
                      start_up=True)
    from pneumaquad.locomotion.course_kernels import gait_track

    start = sim.time - 12.0  # a steady cycle
    hold = HeadingHold(sim, lambda times: np.tile(standing, (len(times), 1)), gain=0.0,
                       track=gait_track(gait, start, 30.0), turn_leak=0.5)
    hold.rotation = -0.1
    chunk = sim.time + sim.control_step * np.arange(1, 11)
    hold(chunk)
    before = stance_travel(gait, np.array([sim.time - start]))[0]
    sim.step(500)
    rows = hold(sim.time + sim.control_step * np.arange(1, 11))
    after = stance_travel(gait, np.array([sim.time - start]))[0]
    assert np.allclose(hold.leg_turns, 0.5 * 0.1 * (after - before), atol=1e-9)
    assert np.isfinite(rows).all()


def test_level_ground_moves_nothing_and_a_slope_does() -> None:
    """placement_step on four feet in a plane: tilted 0.9° (below LEVEL_SLOPE) the body
    stays where the plan puts it, rows unchanged; tilted 5° it moves uphill by h·tan θ
    (blend 1, no limit)."""
    from pneumaquad.gait.crawl import CrawlGait
    from pneumaquad.locomotion.body_placement import LEVEL_SLOPE
    from pneumaquad.locomotion.course_kernels import placement_step
    from pneumaquad.locomotion.feedback_kernels import gait_timing
    from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables
    from pneumaquad.robot.legs import leg_dh_table

    robot = build_robot(load_robot("crr-quadruped"), "quadruped")
    tables = stack_leg_tables([leg_dh_table(robot, leg) for leg in robot.legs])
    feet_xy = np.array([[0.35, 0.4], [0.35, -0.4], [-0.4, 0.4], [-0.4, -0.4]])
    gait = CrawlGait(np.column_stack([feet_xy, np.zeros(4)]), duty_factor=0.9, period=8.0,
                     stride=0.1, step_height=0.04)
    rows = np.tile(np.radians([0.0, -20.0, 80.0]), (10, 4))
    centre = np.array([0.0, 0.0, 0.38])
    identity = np.eye(3).ravel()
    for degrees, moves in ((0.9, False), (5.0, True)):
        slope = math.radians(degrees)
        sites = np.column_stack([feet_xy, feet_xy[:, 0] * math.tan(slope)])
        uphill, corrected = np.zeros(3), rows.copy()
        assert placement_step(corrected, -1.0, gait_timing(gait), sites,
                              np.arange(4, dtype=np.int64), centre, identity, uphill, 1.0,
                              1.0, LEVEL_SLOPE, np.zeros((3, 9)), np.zeros((4, 3)), tables,
                              chain_workspace()) == -1
        if not moves:
            assert np.all(uphill == 0.0) and np.array_equal(corrected, rows)
            continue
        normal = ground_plane(sites)
        height = float((centre - sites.mean(axis=0)) @ normal)
        assert uphill == pytest.approx(uphill_offset(normal, height), abs=1e-14)
        assert np.linalg.norm(uphill) == pytest.approx(height * math.tan(slope), rel=1e-12)
        assert not np.array_equal(corrected, rows)


def test_the_walking_feedback_loads_the_compiled_code_its_calls_use() -> None:
    """Each feedback object loads its kernel's machine code where it is built
    (core.jit.load_compiled) for the argument types of its calls: calling it afterwards
    loads nothing more (a type that differed would add a signature)."""
    from pneumaquad.locomotion.body_placement import BodyPlacement
    from pneumaquad.locomotion.course_kernels import (
        cross_track_error,
        gait_track,
        hold_step,
        placement_step,
    )
    from pneumaquad.locomotion.feedback_kernels import swing_step
    from pneumaquad.locomotion.heading_control import HeadingHold
    from pneumaquad.locomotion.stance_control import StanceController
    from pneumaquad.locomotion.stance_kernels import stance_step
    from pneumaquad.locomotion.swing_control import SwingHeightCorrection
    from pneumaquad.locomotion.walk import robot_gait

    sim, standing = _standing_simulation()
    gait = robot_gait(sim.robot, speed=0.02, heading=0.0, duty_factor=0.9, period=8.0,
                      step_height=0.04, angles=np.radians([0.0, -20.0, 80.0]),
                      minimum_margin=0.06, lift_fraction=0.25, transfer_gap=0.04,
                      start_up=True)
    start = sim.time
    references = StanceController(sim, gait, start,
                                  lambda times: np.tile(standing, (len(times), 1)))
    references = SwingHeightCorrection(sim, gait, start, references)
    references = BodyPlacement(sim, gait, start, references)
    references = HeadingHold(sim, references, track=gait_track(gait, start, 8.0))
    kernels = (stance_step, swing_step, placement_step, hold_step, cross_track_error)
    loaded = [set(kernel.signatures) for kernel in kernels]
    assert all(loaded)
    for _ in range(3):
        rows = references(sim.time + sim.control_step * np.arange(1, 11))
        sim.step(10, rows, 0)
    assert [set(kernel.signatures) for kernel in kernels] == loaded
