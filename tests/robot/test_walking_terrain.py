"""The quadruped walks each terrain of the issue with the default gait (slow: 1-2 minutes of
simulation each). Success is judged by :func:`pneumaquad.locomotion.walking.walking_outcome`:
no fall, static margin negative less than 5 % of the time, stance feet sliding less than
10 cm per metre, no joint stuck at a limit, at least 90 % of the distance."""

from __future__ import annotations

from pathlib import Path

import pytest

from pneumaquad.locomotion.walking import (
    WalkSettings,
    tip_over_series,
    walking_outcome,
    walking_phases,
)
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.simulation import RobotSimulation


@pytest.mark.slow
@pytest.mark.parametrize(("environment", "distance"),
                         [("flat", 1.0), ("ramp", 1.6), ("rough", 2.8)])
def test_the_quadruped_walks_the_terrain(tmp_path: Path, environment: str,
                                         distance: float) -> None:
    robot = build_robot(load_robot("crr-quadruped"), "quadruped", environment=environment)
    sim = RobotSimulation(robot)
    settings = WalkSettings(distance=distance)
    phases, plan = walking_phases(sim, settings)
    run = run_phases(sim, phases, tmp_path, f"walk-{environment}")
    tip_over = tip_over_series(run.recording, run.summary, robot, plan)
    outcome = walking_outcome(run.recording, run.summary, settings, robot, tip_over)
    assert outcome["success"], outcome
    assert outcome["time with negative tip-over margin [%]"] < 1.0
    assert outcome["air per metre [NL/m]"] < 10.0  # measured 6.1-6.5 NL/m
    # the walk ends where asked, within one stride (speed x duty factor x period)
    assert abs(outcome["distance error [m]"]) <= outcome["stride [m]"]


@pytest.mark.slow
@pytest.mark.parametrize("heading", [
    pytest.param(90.0, marks=pytest.mark.xfail(
        strict=True, reason="no verified stance: the four-legged rise into the sideways "
        "posture ends 3.8 cm low, a front beta 15° off")),
    180.0,
    pytest.param(270.0, marks=pytest.mark.xfail(
        strict=True, reason="slip: a stance foot slides 7.4 cm over 0.44 m (limit 10 cm/m)")),
])
def test_the_quadruped_walks_every_heading(tmp_path: Path, heading: float) -> None:
    """Sideways and backwards at the default speed: the gait's roles and posture follow
    the heading (gait.crawl.travel_quarter, locomotion.reach.choose_posture)."""
    import math

    robot = build_robot(load_robot("crr-quadruped"), "quadruped", environment="flat")
    sim = RobotSimulation(robot)
    settings = WalkSettings(distance=0.5, heading=math.radians(heading))
    phases, _ = walking_phases(sim, settings)
    run = run_phases(sim, phases, tmp_path, f"walk-{heading:g}")
    outcome = walking_outcome(run.recording, run.summary, settings, robot)
    assert outcome["success"], outcome
    assert abs(outcome["distance error [m]"]) <= outcome["stride [m]"]
