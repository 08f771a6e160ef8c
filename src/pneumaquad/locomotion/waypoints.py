"""A walk through a list of waypoints: straight crawls between them, the feet re-placed
at each.

Each walk holds the yaw it begins with and walks its leg of the path at the heading that
points from one waypoint to the next (the omnidirectional crawl, :mod:`.walking`), at the
speed, at most the one asked, that makes the leg a whole number of gait cycles, so that
each walk ends where planned. Between two legs of the path the feet move from where the
first walk left them to where the second begins, a foot at a time
(:func:`.replacement.replacement_phases`), its footholds turned so that the body ends at
the yaw the robot lay in (walks holding that yaw themselves began with a heading
correction of up to 3°, and a sideways walk after a backward one failed on its margin);
the legs shed their internal forces (:func:`.walking.settled_hold`), and the next walk
begins from a verified stance. Each walk holds its course from where it begins; the
errors of the walks add up, and each waypoint is judged against one stride
(:func:`waypoint_outcome`).

Waypoints are (x, y) [m] in the frame of the robot's start: x forward, y to the left,
from the body's position when the first walk begins (its planned sway taken out).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pneumaquad.gait.crawl import CrawlGait, body_sway
from pneumaquad.robot.experiment import Phase
from pneumaquad.robot.simulation import RobotSimulation

from .reach import UnreachablePlanError
from .replacement import replacement_phases
from .walk import WalkPlan
from .walk_settings import WalkSettings, WalkSettingsError
from .walking import (
    planned_walk,
    reachable_plan,
    stance_hold,
    stand_up_into,
    walk_phase,
    walking_outcome,
)

__all__ = ["PathLeg", "parse_waypoints", "waypoint_outcome", "waypoint_phases",
           "waypoint_settings"]


@dataclass(frozen=True)
class PathLeg:
    """One straight walk of a waypoint path: its settings, gait, plan and phase name."""

    settings: WalkSettings
    gait: CrawlGait
    plan: WalkPlan
    phase: str
    target: np.ndarray  # (2,) [m] the waypoint it ends at, start frame
    posture: np.ndarray  # (3,) [rad] the walking posture it is planned about


def parse_waypoints(text: str) -> np.ndarray:
    """Waypoints (n, 2) [m] from ``"x,y; x,y; ..."`` (metres).

    Raises
    ------
    ValueError
        Naming the item that is not two numbers.
    """
    points = []
    for item in (part.strip() for part in text.split(";")):
        if not item:
            continue
        try:
            x, y = (float(value) for value in item.split(","))
        except ValueError:
            raise ValueError(f"waypoint {item!r}: expected two numbers in metres, 'x,y'") \
                from None
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError(f"waypoint {item!r}: expected finite numbers")
        points.append((x, y))
    if not points:
        raise ValueError("no waypoints: expected 'x,y; x,y; ...' in metres")
    return np.array(points)


def waypoint_settings(settings: WalkSettings, waypoints: np.ndarray) -> list[WalkSettings]:
    """The settings of each straight walk of the path from (0, 0) through ``waypoints``:
    the heading towards the next waypoint, the distance to it and the speed, at most
    ``settings.speed``, that covers it in whole gait cycles.

    Raises
    ------
    WalkSettingsError
        For two waypoints closer than 1 cm, or a turn asked with waypoints.
    """
    if settings.turning_in_place or settings.yaw_rate != 0.0:
        raise WalkSettingsError("waypoints are walked without turning: leave out --turn "
                                "and --yaw-rate", ("turn", "yaw_rate"))
    legs, here = [], np.zeros(2)
    for point in np.asarray(waypoints, dtype=float):
        step = point - here
        distance = float(np.hypot(*step))
        if distance < 0.01:
            raise WalkSettingsError(
                f"waypoint ({point[0]:g}, {point[1]:g}) m is {distance * 100:.2g} cm from "
                f"the one before: at least 1 cm apart", ("waypoints",))
        legs.append(_whole_cycles(replace(settings, heading=math.atan2(step[1], step[0]),
                                          distance=distance)))
        here = point
    return legs


def _whole_cycles(settings: WalkSettings) -> WalkSettings:
    """``settings`` at the speed, at most the one asked, that walks its distance in whole
    gait cycles (a slower walk is a shorter stride: it reaches no further)."""
    cycles = math.ceil(settings.distance / (settings.speed * settings.period) - 1e-9)
    return replace(settings, speed=settings.distance / (max(1, cycles) * settings.period))


def waypoint_phases(simulation: RobotSimulation, settings: WalkSettings,
                    waypoints: np.ndarray) -> tuple[list[Phase], list[PathLeg]]:
    """Stand up, walk to each waypoint in turn, stop (module docstring); returns the
    phases and the path's legs (their walk phases are ``"walk 1"``, ``"walk 2"``, …).

    Raises
    ------
    WalkSettingsError
        Settings a leg of the path cannot walk: out of reach (naming the leg of the path),
        refused by the gait, or a re-placement of the feet that finds no stable sway.
    """
    robot = simulation.robot
    path: list[PathLeg] = []
    for number, (leg_settings, point) in enumerate(
            zip(waypoint_settings(settings, waypoints), waypoints, strict=True), start=1):
        where = f"to waypoint {number} ({point[0]:g}, {point[1]:g}) m"
        try:
            walked, posture = reachable_plan(robot, leg_settings)
            if walked.period != leg_settings.period:  # a shorter cycle: whole cycles again
                walked, posture = reachable_plan(robot, _whole_cycles(walked))
            if posture is None:
                raise UnreachablePlanError("no posture reaches the plan")
            gait, plan, posture = planned_walk(robot, walked, posture)
        except UnreachablePlanError as error:
            raise WalkSettingsError(
                f"the legs cannot walk {where} (heading "
                f"{math.degrees(leg_settings.heading):g}°): {error}",
                ("waypoints", "speed", "period")) from None
        except ValueError as error:
            raise WalkSettingsError(f"the gait cannot walk {where}: {error}",
                                    ("waypoints",)) from None
        path.append(PathLeg(walked, gait, plan, f"walk {number}", np.asarray(point),
                            posture))
    first = path[0]
    phases = stand_up_into(simulation, first.settings, first.plan, first.posture)
    closed = np.ones(robot.joint_count, dtype=bool)
    time = sum(phase.duration for phase in phases)
    phases.append(walk_phase(simulation, first.settings, first.gait, first.plan, time,
                             first.phase))
    time += phases[-1].duration
    for before, after in itertools.pairwise(path):
        try:
            # the body ends where the next walk's plan starts: its sway differs
            moves = replacement_phases(
                simulation, before.plan.references[-1], after.plan.references[0], time,
                after.gait.com_offset, f"re-place {after.phase}",
                body_move=(_sway_at(after.gait, 0.0)
                           - _sway_at(before.gait, before.settings.duration())),
                heading=0.0)  # and turned back to the yaw the robot lay in
        except UnreachablePlanError as error:
            raise WalkSettingsError(f"the feet cannot be re-placed for {after.phase}: "
                                    f"{error}", ("waypoints",)) from None
        phases += moves
        time += sum(phase.duration for phase in moves)
        held = stance_hold(simulation, after.plan.references[0], settings)
        phases += [replace(phase, name=f"{phase.name} before {after.phase}")
                   for phase in held]
        time += sum(phase.duration for phase in held)
        phases.append(walk_phase(simulation, after.settings, after.gait, after.plan, time,
                                 after.phase))
        time += phases[-1].duration
    phases.append(Phase("stop", 1.0, path[-1].plan.references[-1], closed))
    return phases, path


def _sway_at(gait: CrawlGait, time: float) -> np.ndarray:
    """The planned sway (2,) [m] of ``gait`` at gait ``time`` [s]."""
    return body_sway(gait, np.array([time]))[0]


def waypoint_outcome(recording: dict[str, np.ndarray], summary: dict[str, Any],
                     simulation: RobotSimulation, path: list[PathLeg]) -> dict[str, Any]:
    """Success or failure of a waypoint walk.

    Each leg of the path is judged as a walk (:func:`.walking.walking_outcome`: fall,
    margin, slip, joint limits, distance); the body's position where each walk ends (the
    thorax, its planned sway taken out, from where the first walk began) is compared with
    the waypoint: **missed waypoint** beyond one stride (speed·β·T) of it. The run
    succeeds when every walk did and no waypoint was missed.
    """
    times = recording["time [s]"]
    thorax = np.column_stack([recording["thorax x [m]"], recording["thorax y [m]"]])
    phases = summary["phases"]
    legs, reasons = [], []
    origin = None
    for number, leg in enumerate(path, start=1):
        if leg.phase not in phases:
            reasons.append(f"{leg.phase} did not run")
            break
        window = phases[leg.phase]
        start, duration = window["start [s]"], window["duration [s]"]
        first = int(np.searchsorted(times, start))
        last = int(np.searchsorted(times, start + duration, side="right")) - 1
        if origin is None:
            origin = thorax[first] - _sway_at(leg.gait, 0.0)
        reached = thorax[last] - _sway_at(leg.gait, duration) - origin
        judged = walking_outcome(recording, summary, leg.settings, simulation.robot,
                                 phase=leg.phase)
        stride = leg.settings.speed * leg.settings.duty_factor * leg.settings.period
        error = float(np.hypot(*(reached - leg.target)))
        judged.update({"waypoint [m]": leg.target.tolist(), "reached [m]": reached.tolist(),
                       "waypoint error [m]": error, "heading [deg]":
                       math.degrees(leg.settings.heading), "speed [m/s]": leg.settings.speed})
        legs.append(judged)
        if not judged["success"]:
            reasons += [f"walk {number}: {reason}" for reason in judged["reasons"]]
        if error > stride:
            reasons.append(f"missed waypoint {number} by {error:.3f} m (more than a "
                           f"stride, {stride:.3f} m)")
    return {"success": not reasons, "reasons": reasons or ["reached every waypoint"],
            "legs": legs, "start [m]": [] if origin is None else origin.tolist(),
            "final waypoint error [m]": legs[-1]["waypoint error [m]"] if legs else math.nan}
