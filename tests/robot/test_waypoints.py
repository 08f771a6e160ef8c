"""Waypoint walks: parsing, the legs of the path, the re-placement of the feet between
two walks (its sway keeps the centre of mass inside the three feet down), and one path
walked (slow)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.locomotion.replacement import REPLACEMENT_MARGIN, _sways
from pneumaquad.locomotion.walk_settings import WalkSettings, WalkSettingsError
from pneumaquad.locomotion.waypoints import parse_waypoints, waypoint_settings


def test_waypoints_parse_and_bad_ones_are_named() -> None:
    assert parse_waypoints("0.5,0; 0.5, 0.5;") == pytest.approx(
        np.array([[0.5, 0.0], [0.5, 0.5]]))
    for text, named in (("0.5", "'0.5'"), ("0.5,x", "'0.5,x'"), ("", "no waypoints"),
                        ("1,2,3", "'1,2,3'"), ("nan,0", "finite")):
        with pytest.raises(ValueError, match=named):
            parse_waypoints(text)


def test_each_leg_of_the_path_points_at_its_waypoint_in_whole_cycles() -> None:
    settings = WalkSettings(speed=0.02, period=8.0)
    points = np.array([[0.5, 0.0], [0.5, 0.5], [-0.1, 0.5]])
    legs = waypoint_settings(settings, points)
    assert [math.degrees(leg.heading) for leg in legs] == pytest.approx([0.0, 90.0, 180.0])
    assert [leg.distance for leg in legs] == pytest.approx([0.5, 0.5, 0.6])
    for leg in legs:
        cycles = leg.duration() / leg.period
        assert cycles == round(cycles) >= 1
        assert leg.speed * leg.duration() == pytest.approx(leg.distance, rel=1e-12)
        assert leg.speed <= settings.speed  # never faster than asked (a longer stride)
    with pytest.raises(WalkSettingsError, match="at least 1 cm apart"):
        waypoint_settings(settings, np.array([[0.5, 0.0], [0.5, 0.005]]))
    with pytest.raises(WalkSettingsError, match="without turning"):
        waypoint_settings(WalkSettings(turn=1.0), points)


def test_the_sway_keeps_the_centre_of_mass_inside_the_feet_left_down() -> None:
    """A square stance 0.8 × 0.8 m, centre of mass at its middle: lifting a left foot
    leaves a triangle whose diagonal passes through the centre, so the body must sway
    right by the margin over cos 45° (the distance to the diagonal grows as sway/√2)."""
    feet = np.array([[0.4, 0.4], [0.4, -0.4], [-0.4, 0.4], [-0.4, -0.4]])
    before = np.array([feet, feet])  # the feet before each of the two steps
    sway = next(_sways(before, [2, 0], -1.0, np.zeros(2)))  # the shortest
    assert sway[0] == 0.0 and sway[1] < 0.0  # to the right, away from the lifting feet
    needed = REPLACEMENT_MARGIN * math.sqrt(2.0)
    assert needed <= -sway[1] < needed + 0.005  # the search's 5 mm grid
    narrow = feet * np.array([1.0, 0.05])  # feet nearly in a line: no sway is enough
    assert next(_sways(np.array([narrow, narrow]), [2, 0], -1.0, np.zeros(2)), None) is None


def _forward_then_sideways():
    """A standing quadruped's simulation, the last pose of a 0.3 m forward walk, the first
    pose of a 0.3 m walk to the left after it, and that walk's centre of mass offset."""
    from pneumaquad.locomotion.walk import plan_walk
    from pneumaquad.locomotion.walking import reachable_plan, walking_gait
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.simulation import RobotSimulation

    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped"))
    plans = []
    for leg in waypoint_settings(WalkSettings(), np.array([[0.3, 0.0], [0.3, 0.3]])):
        walked, posture = reachable_plan(simulation.robot, leg)
        gait = walking_gait(simulation.robot, walked, posture)
        plans.append((gait, plan_walk(simulation.robot, gait, walked.duration())))
    return (simulation, plans[0][1].references[-1], plans[1][1].references[0],
            plans[1][0].com_offset)


def test_the_feet_are_re_placed_one_at_a_time_into_the_next_pose() -> None:
    """Between a forward walk and a sideways one: for each leg a sway over the other three
    feet and its step (left legs first, rear before front), then into the next pose; one
    leg moves per step phase, the feet stand still in a sway, and the last phase ends in
    the next walk's first pose."""
    from pneumaquad.locomotion.replacement import replacement_phases

    simulation, start, end, centre = _forward_then_sideways()
    robot = simulation.robot
    phases = replacement_phases(simulation, start, end, 10.0, centre)
    names = [phase.name for phase in phases]
    order = ["rear_left", "front_left", "rear_right", "front_right"]
    assert names == [f"re-place: {part}" for leg in order
                     for part in (f"sway for {leg}", leg)] + ["re-place: into the next pose"]
    time = 10.0
    for phase in phases:
        begin = phase.references(np.array([time]))[0]
        after = phase.references(np.array([time + phase.duration]))[0]
        moved = np.flatnonzero(np.abs(after - begin).reshape(4, 3).max(axis=1) > 1e-12)
        if phase.name.endswith(("left", "right")) and "sway" not in phase.name:
            leg = robot.legs.index(phase.name.split(": ")[1])
            assert moved.tolist() == [leg]
        if "sway" in phase.name:  # the body moves over feet that stay: every leg's joints
            simulation.set_pose(begin)
            feet_before = simulation.foot_positions() - simulation.data.xpos[
                robot.thorax_id]
            simulation.set_pose(after)
            feet_after = simulation.foot_positions() - simulation.data.xpos[
                robot.thorax_id]
            moves = feet_after - feet_before  # the feet relative to the body: all alike
            assert np.allclose(moves, moves[0], atol=0.011)
        time += phase.duration
    assert phases[-1].references(np.array([time]))[0] == pytest.approx(end, abs=1e-12)
    assert phases[0].references(np.array([10.0]))[0] == pytest.approx(start, abs=1e-12)


@pytest.mark.slow
def test_walks_an_l_shaped_path_through_two_waypoints(tmp_path: Path) -> None:
    """0.5 m ahead, then 0.5 m to the left: both walks succeed, the feet re-placed
    between them, and each waypoint is reached within a stride."""
    from pneumaquad.locomotion.walk_run import run_waypoints
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.simulation import RobotSimulation

    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped"))
    walk = run_waypoints(simulation, WalkSettings(), np.array([[0.5, 0.0], [0.5, 0.5]]),
                         tmp_path / "path")
    outcome = walk.outcome
    assert outcome is not None and outcome["success"], outcome
    assert outcome["final waypoint error [m]"] < 0.1
    assert all(check["verified"] for check in walk.run.summary["checks"].values())
    assert (tmp_path / "path" / "waypoints.png").exists()


def test_the_footholds_turn_the_body_back_to_its_heading() -> None:
    """With ``heading`` given, the re-placement measures the yaw when it begins and turns
    the new footholds about the body by minus its error: the feet of the pose before the
    last move keep their distances to each other and are turned by −error (so the move
    into the next pose turns the body back); without it, nothing is turned."""
    from pneumaquad.locomotion.replacement import _planned, replacement_phases
    from pneumaquad.locomotion.walk import thorax_rotation
    from pneumaquad.robot.legs import leg_dh_table, thorax_frame_points

    simulation, start, end, centre = _forward_then_sideways()
    robot = simulation.robot
    error = math.radians(4.0)
    import mujoco

    from pneumaquad.robot.recording import thorax_attitude

    yawed = np.zeros(4)  # the thorax's placement turned by +4° about the vertical
    mujoco.mju_mulQuat(yawed, np.array([math.cos(error / 2), 0.0, 0.0, math.sin(error / 2)]),
                       simulation.model.body_quat[robot.thorax_id])
    simulation.set_pose(start, thorax_quaternion=yawed)
    assert float(thorax_attitude(simulation)[2]) == pytest.approx(error, abs=1e-9)

    tables = [leg_dh_table(robot, leg) for leg in robot.legs]
    to_body = thorax_rotation(robot)

    def footholds(phases) -> np.ndarray:  # feet (body frame x, y) before the last move
        pose = phases[-1].references(np.array([phases[-1].references.plan.arguments[2]]))[0]
        return np.array([(to_body @ thorax_frame_points(table, pose[3 * k: 3 * k + 3]))[:2]
                         for k, table in enumerate(tables)])

    turned = replacement_phases(simulation, start, end, 0.0, centre, heading=0.0)
    unturned = replacement_phases(simulation, start, end, 0.0, centre)
    feet_turned, feet_unturned = footholds(turned), footholds(unturned)
    left, right = robot.legs.index("front_left"), robot.legs.index("rear_left")
    distances = [np.linalg.norm(feet[left] - feet[right]) for feet in (feet_turned,
                                                                      feet_unturned)]
    assert distances[0] == pytest.approx(distances[1], abs=0.002)  # a turn, not a stretch
    angles = [math.atan2(*(feet[left] - feet[right])[::-1]) for feet in (feet_turned,
                                                                         feet_unturned)]
    assert angles[0] - angles[1] == pytest.approx(-error, abs=math.radians(0.3))
    direct = _planned(simulation, start, end, 0.0, centre, "re-place", None, turn=-error)
    last = direct[-1].references(np.array([0.0]))[0]
    assert last == pytest.approx(turned[-1].references(np.array([0.0]))[0], abs=1e-12)
