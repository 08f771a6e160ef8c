"""The quadruped walking with the crawl gait on its 12 pneumatic joints.

:func:`walking_phases` stands the robot up (:func:`.scenarios.stand_up_phases`) into the
first pose of the lateral-sequence wave gait of :mod:`pneumaquad.gait` (duty factor ≥ 0.75,
body sway to a planned static margin, a start-up cycle from the symmetric stance), then
plays the gait as joint references, with a force-controlled stance
(:mod:`.stance_control`) and swing and heading corrections; :func:`walking_outcome`
judges the run honestly: how far the robot went, whether it fell, slipped, hit a joint
limit, or lost static stability.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from pneumaquad.gait.crawl import CrawlGait
from pneumaquad.gait.stability import STANCE_FORCE, support_margins
from pneumaquad.locomotion.walk import WalkPlan, plan_walk, robot_gait
from pneumaquad.robot.builder import RobotModel
from pneumaquad.robot.experiment import Phase
from pneumaquad.robot.scenarios import stand_up_phases
from pneumaquad.robot.simulation import RobotSimulation
from pneumaquad.robot.stance_check import StanceCheck
from pneumaquad.robot.stand_up import smooth_ramp

from .body_placement import BodyPlacement
from .capacity import rise_in_pairs
from .course_kernels import gait_track
from .heading_control import HeadingHold
from .reach import (
    LIMIT_BAND,
    LIMIT_SHARE,
    REACH_TOLERANCE,
    check_reach,
    choose_posture,
    plan_miss,
)
from .stance_control import StanceController, StanceSettle
from .swing_control import SwingHeightCorrection
from .walk_settings import TURN_RATE, TURN_TOLERANCE, WalkSettings

__all__ = [
    "TURN_RATE",
    "TURN_TOLERANCE",
    "WALKING_ANGLES",
    "WalkSettings",
    "contact_slide",
    "gait_support_margins",
    "planned_walk",
    "reachable_plan",
    "settled_hold",
    "stance_hold",
    "stand_up_into",
    "tip_over_series",
    "walk_phase",
    "walking_gait",
    "walking_outcome",
    "walking_phases",
]

#: Alpha, beta, gamma [rad] the gait is planned about: every IK sample stays reachable
#: (the standing gamma of 90° is too close to its 95° limit to lift and sway).
WALKING_ANGLES = np.radians([0.0, -20.0, 80.0])


def walking_gait(robot: RobotModel, settings: WalkSettings, angles: np.ndarray) -> CrawlGait:
    """The crawl of ``settings`` for ``robot``, planned about the posture ``angles``
    (alpha, beta, gamma) [rad], with its start-up cycle."""
    return robot_gait(robot, speed=settings.body_speed(), heading=settings.heading,
                      duty_factor=settings.duty_factor, period=settings.period,
                      step_height=settings.step_height, angles=angles,
                      minimum_margin=settings.minimum_margin,
                      lift_fraction=settings.lift_fraction,
                      transfer_gap=settings.transfer_gap, start_up=True,
                      yaw_rate=settings.body_yaw_rate())


#: Cycle periods, as fractions of the one asked, that :func:`reachable_plan` tries in
#: turn: a shorter cycle at the same speed is a shorter stride and swing (headings 60° and
#: 240° are out of reach by 14 mm with the default 8 s cycle, within reach with 7 s).
PERIOD_SCALES = (1.0, 0.875, 0.75)


def reachable_plan(robot: RobotModel,
                   settings: WalkSettings) -> tuple[WalkSettings, np.ndarray | None]:
    """``settings``, or with the first shorter cycle of :data:`PERIOD_SCALES` whose plan
    the legs reach (within :data:`.reach.REACH_TOLERANCE`, about the posture
    :func:`.reach.choose_posture` picks), at the same speed, and that posture [rad];
    ``settings`` unchanged and None when none does (the plan is then refused,
    :func:`.reach.check_reach`)."""
    for scale in PERIOD_SCALES:
        candidate = replace(settings, period=settings.period * scale)

        def gait_for(angles: np.ndarray, candidate: WalkSettings = candidate) -> CrawlGait:
            return walking_gait(robot, candidate, angles)

        try:
            posture = choose_posture(robot, gait_for, WALKING_ANGLES)
            # the default posture is chosen only when its plan is within reach
            if (np.array_equal(posture, WALKING_ANGLES)
                    or plan_miss(robot, gait_for(posture)) <= REACH_TOLERANCE):
                return candidate, posture
        except ValueError:  # the gait refuses these settings (e.g. its margin)
            continue
    return settings, None


#: The phase of a staged walk start that moves the legs from their mean pose into the
#: gait's first pose.
TO_FIRST_POSE = "to the first pose"
#: The phase of a staged walk start that holds the stance under force control.
SETTLE = "settle"


def leg_posture(pose: np.ndarray) -> np.ndarray:
    """The mean (alpha, beta, gamma) [rad] over the legs of a pose (joints,)."""
    return np.asarray(pose, dtype=float).reshape(-1, 3).mean(axis=0)


def walking_phases(
    simulation: RobotSimulation, settings: WalkSettings, posture: np.ndarray | None = None
) -> tuple[list[Phase], WalkPlan]:
    """Stand up into the gait's first pose, walk, stop; returns the phases and the plan.

    ``posture`` [rad]: the walking posture when the caller has chosen it already
    (:func:`reachable_plan`); by default :func:`.reach.choose_posture`'s.

    The robot stands up into the first pose, a pair of legs at a time where the supply is
    short of what the four-legged rise needs (:func:`.capacity.rise_in_pairs`); where the
    gait's posture is not the default one (sideways), always a pair at a time, into the
    legs' mean pose and then into the first pose. The walk begins only from
    a verified stance: its phase's gate is a
    :class:`~pneumaquad.robot.stance_check.StanceCheck` of the first pose (the verdict in
    the summary's ``"checks"``; a stance out of its limits ends the run before the walk).

    The gait is planned about :data:`WALKING_ANGLES`, or about another posture where the
    legs cannot reach that plan (:func:`.reach.choose_posture`, e.g. walking sideways).

    Raises
    ------
    UnreachablePlanError
        When the legs cannot reach the plan about any posture (:func:`.reach.check_reach`:
        the leg, its phase and the joint limit).
    ValueError
        Settings the gait refuses (:class:`pneumaquad.gait.crawl.CrawlGait`).
    """
    gait, plan, posture = planned_walk(simulation.robot, settings, posture)
    phases = stand_up_into(simulation, settings, plan, posture)
    walk_start = sum(phase.duration for phase in phases)
    phases += [
        walk_phase(simulation, settings, gait, plan, walk_start),
        Phase("stop", 1.0, plan.references[-1],
              np.ones(simulation.robot.joint_count, dtype=bool)),
    ]
    return phases, plan


def planned_walk(robot: RobotModel, settings: WalkSettings, posture: np.ndarray | None = None
                 ) -> tuple[CrawlGait, WalkPlan, np.ndarray]:
    """The gait of ``settings`` about ``posture`` [rad] (by default
    :func:`.reach.choose_posture`'s), its plan for the walk's duration, and the posture;
    raises :class:`~.reach.UnreachablePlanError` when the legs cannot reach the plan
    (:func:`.reach.check_reach`) and ValueError for settings the gait refuses."""

    def gait_for(angles: np.ndarray) -> CrawlGait:
        return walking_gait(robot, settings, angles)

    if posture is None:
        posture = choose_posture(robot, gait_for, WALKING_ANGLES)
    gait = gait_for(posture)
    plan = plan_walk(robot, gait, settings.duration())
    check_reach(robot, gait, plan.cycle, plan.start_up)
    return gait, plan, posture


def stand_up_into(simulation: RobotSimulation, settings: WalkSettings, plan: WalkPlan,
                  posture: np.ndarray) -> list[Phase]:
    """The phases that stand the robot up from lying into ``plan``'s first pose and hold
    it (:func:`walking_phases`: a pair of legs at a time where the supply is short or the
    ``posture`` [rad] is not the default one, the hold of a staged rise settled)."""
    robot = simulation.robot
    closed = np.ones(robot.joint_count, dtype=bool)
    first = plan.references[0]
    symmetric = leg_posture(first)
    default_posture = bool(np.allclose(posture, WALKING_ANGLES))
    staged = not default_posture or rise_in_pairs(simulation, symmetric)
    if not default_posture:
        # A pair at a time into the legs' mean pose, then into the first pose: rising
        # straight into a sideways first pose (swayed along the body) left a rear alpha
        # 7.6° off (heading 270°), rising on four legs 3.6-3.9 cm low.
        phases = stand_up_phases(simulation, hold=3.0, posture=False,
                                 standing_angles=symmetric, check=False, staged=True)
        begin = sum(phase.duration for phase in phases)
        phases.append(Phase(TO_FIRST_POSE, 4.0, smooth_ramp(
            np.tile(symmetric, len(robot.legs)), first, begin, 2.0), closed))
    else:
        # Straight into the gait's first pose, the symmetric stance of its start-up (a
        # separate move from a standing pose to the walking pose dragged the feet), a pair
        # of legs at a time where the supply is short.
        phases = stand_up_phases(simulation, hold=3.0, posture=False, standing_angles=first,
                                 check=False, staged=staged)
    if staged and settings.stance_control is not None:
        # the staged rise's steps leave the legs pushing against each other through the
        # feet: the first half of the hold sheds those forces under force control
        at = [phase.name for phase in phases].index("hold")
        phases[at:at + 1] = settled_hold(simulation, phases[at], settings)
    return phases


def settled_hold(simulation: RobotSimulation, hold: Phase,
                 settings: WalkSettings) -> list[Phase]:
    """``hold`` split in two: its first half under force control
    (:class:`.stance_control.StanceSettle`: the legs stop pushing against each other
    through the feet's friction), its second half bringing the joints back onto its pose
    under position control."""
    return [replace(hold, name=SETTLE, duration=hold.duration / 2, feedback=True,
                    references=StanceSettle(simulation, hold.references,
                                            settings.stance_control)),
            replace(hold, duration=hold.duration / 2)]


def stance_hold(simulation: RobotSimulation, pose: np.ndarray,
                settings: WalkSettings, duration: float = 3.0) -> list[Phase]:
    """The hold of ``pose`` [rad] for ``duration`` [s] before a walk begins from it (after
    the feet were re-placed): :func:`settled_hold` when the walk's stance is
    force-controlled, else a plain hold under position control."""
    hold = Phase("hold", duration, pose, np.ones(simulation.robot.joint_count, dtype=bool))
    return [hold] if settings.stance_control is None else settled_hold(simulation, hold,
                                                                      settings)


def walk_phase(simulation: RobotSimulation, settings: WalkSettings, gait: CrawlGait,
               plan: WalkPlan, start: float, name: str = "walk",
               heading: float | None = None) -> Phase:
    """The phase that walks ``plan`` from simulation time ``start`` [s], with the
    feedback ``settings`` asks for (force-controlled stance, swing height from the
    ground, body placement on slopes, heading and course hold) and a
    :class:`~pneumaquad.robot.stance_check.StanceCheck` of the plan's first pose as its
    gate. ``heading`` [rad]: the yaw to hold (default: the yaw the walk begins with; the
    yaw the robot lay in when turning in place)."""
    step = simulation.control_step
    duration = settings.duration()

    last = len(plan.references) - 1

    def walk(times: np.ndarray) -> np.ndarray:
        first, end = (round((float(times[k]) - start) / step) for k in (0, -1))
        if first >= 0 and end <= last and end - first == len(times) - 1:  # a chunk's steps
            return plan.references[first:end + 1].copy()
        index = np.clip(np.round((times - start) / step).astype(int), 0, last)
        return plan.references[index]

    references = walk
    if settings.stance_control is not None:
        references = StanceController(simulation, gait, start, references,
                                      settings.stance_control)
    if settings.swing_from_ground:
        references = SwingHeightCorrection(simulation, gait, start, references)
    if settings.body_placement:
        references = BodyPlacement(simulation, gait, start, references)
    if settings.heading_hold:
        references = HeadingHold(simulation, references,
                                 yaw_rate=settings.body_yaw_rate(),
                                 track=gait_track(gait, start, duration))
        if settings.turning_in_place:  # from the yaw the robot lay in, as it is judged
            references.heading = 0.0
        if heading is not None:
            references.heading = heading
    feedback = (settings.stance_control is not None or settings.swing_from_ground
                or settings.heading_hold or settings.body_placement)
    closed = np.ones(simulation.robot.joint_count, dtype=bool)
    return Phase(name, duration, references, closed, feedback=feedback,
                 gate=StanceCheck(plan.references[0]))


def contact_slide(foot_xy: np.ndarray, loaded: np.ndarray) -> float:
    """Total slide [m] of one foot: the sum, over its stretches of continuous load, of the
    distance between where the stretch began and where it ended.

    Parameters
    ----------
    foot_xy : (n, 2) [m]  foot positions on the ground at the recording instants.
    loaded : (n,) bool  the foot carries load.
    """
    edges = np.flatnonzero(np.diff(np.concatenate([[0], loaded.astype(int), [0]])))
    total = 0.0
    for first, end in zip(edges[::2], edges[1::2], strict=True):
        total += float(np.linalg.norm(foot_xy[end - 1] - foot_xy[first]))
    return total


def gait_support_margins(recording: dict[str, np.ndarray], legs: tuple[str, ...],
                         stance: np.ndarray) -> np.ndarray:
    """Static margin [m] of the measured centre of mass in the support polygon of the feet
    the gait holds on the ground (``stance`` (n, legs) bool per recorded sample), at their
    measured positions, whether or not they carry load: the tip-over margin of the gait.
    """
    feet = np.stack([np.column_stack([recording[f"{leg} foot x [m]"],
                                      recording[f"{leg} foot y [m]"]]) for leg in legs], axis=1)
    com = np.column_stack([recording["centre of mass x [m]"], recording["centre of mass y [m]"]])
    return support_margins(feet, stance, com)


def _walk_window(recording: dict[str, np.ndarray], summary: dict[str, Any],
                 phase: str = "walk") -> tuple[float, np.ndarray]:
    """Start [s] of the walk phase and the recorded samples inside it (bool mask)."""
    times = recording["time [s]"]
    walk = summary["phases"][phase]
    start = walk["start [s]"]
    return start, (times >= start) & (times <= start + walk["duration [s]"])


def tip_over_series(recording: dict[str, np.ndarray], summary: dict[str, Any],
                    robot: RobotModel, plan: WalkPlan, phase: str = "walk") -> np.ndarray:
    """:func:`gait_support_margins` for every recorded sample (NaN outside the walk
    phase ``phase``)."""
    times = recording["time [s]"]
    start, walking = _walk_window(recording, summary, phase)
    step = float(plan.times[1] - plan.times[0]) if plan.times.size > 1 else 1.0
    index = np.clip(np.round((times[walking] - start) / step).astype(int), 0,
                    len(plan.stance) - 1)
    series = np.full(times.shape, np.nan)
    series[walking] = gait_support_margins({k: v[walking] for k, v in recording.items()},
                                           tuple(robot.legs), plan.stance[index])
    return series


def walking_outcome(
    recording: dict[str, np.ndarray], summary: dict[str, Any], settings: WalkSettings,
    robot: RobotModel, tip_over: np.ndarray | None = None, phase: str = "walk",
) -> dict[str, Any]:
    """Success or failure of a walking run, with the reason.

    Criteria: **fall** — thorax below 0.15 m or |roll|, |pitch| above 30° during the walk;
    **margin violation** — the recorded static margin below 0 for more than 5 % of the walk
    (feet carrying load, whole-robot centre of mass); **slip** — loaded feet sliding more
    than 10 cm on the ground per metre travelled (a leg's total of
    :func:`contact_slide`; the path length of loaded feet, which also counts sub-millimetre
    contact jitter, is reported beside it); **joint limit** — a joint
    within 0.5° of a limit for more than 20 % of the walk; the run succeeds when none of
    these happened and the thorax travelled at least 90 % of the planned travel (the whole
    cycles of :meth:`WalkSettings.duration`) along the heading (**too slow** otherwise,
    listed with the other reasons: a robot stalled at an obstacle is too slow whatever else
    happened) and not more than one stride beyond the distance asked (**overshot**). The
    outcome gives the distance error (travelled − asked) and the stride (speed·β·T) it is
    judged against.

    With ``tip_over`` (:func:`tip_over_series` of the run: the margin in the support of
    the feet the gait holds down, loaded or not) it is reported beside the loaded-feet
    margin: a robot
    rocking on a diagonal pair of feet has a negative loaded-feet margin while its
    tip-over margin stays positive (the rocking is bounded by the unloaded feet, a few
    millimetres above the ground). ``phase``: the name of the walk phase judged.
    """
    _, walking = _walk_window(recording, summary, phase)
    direction = np.array([math.cos(settings.heading), math.sin(settings.heading)])
    x, y = recording["thorax x [m]"], recording["thorax y [m]"]
    first, last = np.flatnonzero(walking)[[0, -1]]
    displacement = np.array([x[last] - x[first], y[last] - y[first]])
    travelled = float(direction @ displacement)
    sideways = float(abs(direction[0] * displacement[1] - direction[1] * displacement[0]))
    if settings.yaw_rate != 0.0 and not settings.turning_in_place:
        # an arc: each step's progress along the heading turned with the body
        yaw = np.unwrap(recording["thorax yaw [rad]"][first:last + 1])
        course = settings.heading + yaw[1:] - yaw[0]
        steps = np.column_stack([np.diff(x[first:last + 1]), np.diff(y[first:last + 1])])
        travelled = float(np.sum(steps[:, 0] * np.cos(course) + steps[:, 1] * np.sin(course)))
        sideways = float(abs(np.sum(steps[:, 1] * np.cos(course)
                                    - steps[:, 0] * np.sin(course))))
    fallen = bool(
        np.any(recording["thorax z [m]"][walking] < 0.15)
        or np.any(np.abs(recording["thorax roll [rad]"][walking]) > math.radians(30.0))
        or np.any(np.abs(recording["thorax pitch [rad]"][walking]) > math.radians(30.0))
    )
    margin = recording["stability margin [m]"][walking]
    violated = float(np.mean(~(margin >= 0.0)))
    slip, path = 0.0, 0.0
    for leg in robot.legs:
        loaded = recording[f"{leg} foot normal force [N]"][walking] > STANCE_FORCE
        foot = np.column_stack([recording[f"{leg} foot x [m]"][walking],
                                recording[f"{leg} foot y [m]"][walking]])
        slip = max(slip, contact_slide(foot, loaded))
        moved = np.linalg.norm(np.diff(foot, axis=0), axis=1)
        path = max(path, float(np.sum(moved[loaded[1:] & loaded[:-1]])))
    reasons = []
    if fallen:
        reasons.append("fall")
    if violated > 0.05:
        reasons.append("margin violation")
    if settings.turning_in_place:  # the feet's arc about the body's centre
        radius = float(np.mean([np.hypot(
            recording[f"{leg} foot x [m]"][first] - x[first],
            recording[f"{leg} foot y [m]"][first] - y[first]) for leg in robot.legs]))
        moved = radius * abs(settings.turn)
    else:
        moved = travelled
    if slip > 0.1 * max(moved, 0.1):
        reasons.append("slip")
    at_limit = []
    for name, lower, upper in zip(robot.joint_names, robot.lower_limits(),
                                  robot.upper_limits(), strict=True):
        angle = recording[f"{name} angle [rad]"][walking]
        near = (angle < lower + LIMIT_BAND) | (angle > upper - LIMIT_BAND)
        if np.mean(near) > LIMIT_SHARE:
            at_limit.append(name)
    if at_limit:
        reasons.append("joint limit")
    if tip_over is not None:
        tip = tip_over[walking]
        tip_over_figures = {
            "time with negative tip-over margin [%]": 100.0 * float(np.mean(tip < 0.0)),
            "smallest tip-over margin [m]": float(np.nanmin(tip)),
            "median tip-over margin [m]": float(np.nanmedian(tip)),
        }
    else:
        tip_over_figures = {}
    air = summary["phases"][phase]["air consumed [NL]"]
    outcome = {
        "distance travelled [m]": travelled,
        "sideways drift [m]": sideways,
        "target distance [m]": settings.distance,
        "fell": fallen,
        "time with negative static margin [%]": 100.0 * violated,
        "smallest static margin [m]": float(np.nanmin(margin)) if margin.size else math.nan,
        **tip_over_figures,
        "largest stance-foot slide [m]": slip,
        "largest loaded-foot path [m]": path,
        "joints at a limit": at_limit,
        "air per metre [NL/m]": air / travelled if travelled > 0 else math.nan,
    }
    if settings.turning_in_place:
        yaw = np.unwrap(recording["thorax yaw [rad]"])
        turned = float(yaw[-1] - yaw[0])
        outcome["turn asked [deg]"] = math.degrees(settings.turn)
        outcome["turned [deg]"] = math.degrees(turned)
        outcome["turn error [deg]"] = math.degrees(turned - settings.turn)
        # where the robot stands: the centre of its four feet, all down at the start and
        # the end of a turn (the thorax is swayed off it, and its sway turns with it)
        centres = [np.mean([[recording[f"{leg} foot {axis} [m]"][k] for axis in "xy"]
                            for leg in robot.legs], axis=0) for k in (first, last)]
        outcome["drift [m]"] = float(np.hypot(*(centres[1] - centres[0])))
        outcome["air per metre [NL/m]"] = math.nan
        if abs(turned - settings.turn) > TURN_TOLERANCE:
            reasons.append("turned short" if abs(turned) < abs(settings.turn)
                           else "turned too far")
        outcome["success"] = not reasons
        outcome["reasons"] = reasons or ["turned as asked"]
        return outcome
    stride = settings.speed * settings.duty_factor * settings.period
    planned = settings.duration() * settings.speed
    outcome["planned travel [m]"] = planned
    outcome["distance error [m]"] = travelled - settings.distance
    outcome["stride [m]"] = stride
    if travelled < 0.9 * planned:
        reasons.append("too slow")
    elif travelled > settings.distance + stride:
        reasons.append("overshot")
    outcome["success"] = not reasons
    outcome["reasons"] = reasons or ["reached the distance"]
    return outcome
