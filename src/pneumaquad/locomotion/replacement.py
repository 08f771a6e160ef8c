"""Moving the feet from one stance to another, a leg at a time, the body held over the rest.

Between two walks the feet stand where the first one left them and must stand where the
second one begins (another heading moves the footholds and the sway; another posture, the
whole stance). Dragging them there in joint space would slide loaded feet. Instead
(:func:`replacement_phases`), for each foot in turn (the left ones first, rear before
front, as in the lateral-sequence gait), the body sways away from it (sideways, or turned
up to 60° towards the front or the rear where that is shorter and the legs reach) until
the centre of mass lies inside the triangle of the three feet that stay down with a
margin; the foot lifts, moves to its new foothold on an arc and goes down. The joints
finally move into the second walk's first pose, the feet staying where they were put.

Units: SI and radians; foot positions in the thorax frame of the legs' DH tables, sways
in the body frame.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np
from numpy.typing import NDArray

from pneumaquad.gait.stability import support_margins
from pneumaquad.robot.experiment import Phase
from pneumaquad.robot.legs import leg_dh_table, solve_leg, thorax_frame_points
from pneumaquad.robot.recording import thorax_attitude
from pneumaquad.robot.simulation import RobotSimulation
from pneumaquad.robot.stand_up import smooth_ramp

from .reach import UnreachablePlanError
from .walk import thorax_rotation

__all__ = ["REPLACEMENT_MARGIN", "STEP_TIME", "SWAY_TIME", "foothold_moves",
           "replacement_phases"]

Array = NDArray[np.float64]

#: Static margin [m] of the centre of mass in the three feet that stay down while a foot
#: moves (the gait plans 60 mm; a re-placement step is slower and shorter).
REPLACEMENT_MARGIN = 0.04
#: Duration [s] of a sway of the body, and of the final move into the next pose.
SWAY_TIME = 2.0
#: Duration [s] of one foot's move.
STEP_TIME = 1.5
#: Lift [m] of a moving foot at mid-step.
STEP_LIFT = 0.04
#: Largest sway [m] searched, in 5 mm steps.
LARGEST_SWAY = 0.2


def _feet(tables: list, pose: Array) -> Array:
    """Feet (legs, 3) [m] in the thorax frame of a pose (joints,) [rad]."""
    return np.array([thorax_frame_points(table, pose[3 * k: 3 * k + 3])
                     for k, table in enumerate(tables)])


def foothold_moves(simulation: RobotSimulation, start_pose: Array, end_pose: Array,
                   body_move: Array | None = None) -> Array:
    """How far (legs,) [m] each foot moves on the ground from its place in ``start_pose``
    to its place in ``end_pose`` (joints,) [rad] with the body moved by ``body_move`` (2,)
    [m, body frame x, y] (the horizontal distance; all 0: the body alone moves)."""
    robot = simulation.robot
    tables = [leg_dh_table(robot, leg) for leg in robot.legs]
    to_body = thorax_rotation(robot)
    before = _feet(tables, np.asarray(start_pose, float)) @ to_body.T
    after = _feet(tables, np.asarray(end_pose, float)) @ to_body.T
    if body_move is not None:
        after[:, :2] += np.asarray(body_move, dtype=float)
    return np.hypot(*(after[:, :2] - before[:, :2]).T)


def _pose(tables: list, feet: Array, near: Array) -> Array:
    """Joint angles (joints,) [rad] putting the feet (legs, 3) [m] where asked (clamped IK
    near ``near``); raises :class:`UnreachablePlanError` for a foot more than 10 mm off."""
    pose = np.empty(3 * len(tables))
    for k, table in enumerate(tables):
        result = solve_leg(table, feet[k], near[3 * k: 3 * k + 3])
        reached = thorax_frame_points(table, result.angles)
        if np.linalg.norm(reached - feet[k]) > 0.01:
            raise UnreachablePlanError(
                f"leg {k} cannot reach {np.round(feet[k], 3)} m (thorax frame) while the "
                f"feet are re-placed between two walks")
        pose[3 * k: 3 * k + 3] = result.angles
    return pose


def _sways(feet_body: Array, moving: list[int], lateral: float, centre: Array):
    """Sways (2,) [m, body frame x, y], shortest first, that keep the centre of mass
    ``centre`` (2,) [m, body frame] at least :data:`REPLACEMENT_MARGIN` inside the feet
    left down while each leg of ``moving`` lifts in turn (``feet_body`` (steps, legs, 2):
    the feet before each step). Searched along the body's y axis, to the side ``lateral``
    (±1), and along directions turned up to 60° from it towards the front and the rear
    (5 mm steps); of equal lengths the one nearest the y axis first."""
    steps = len(moving)
    stance = np.ones((steps, feet_body.shape[1]), dtype=bool)
    for step, leg in enumerate(moving):
        stance[step, leg] = False
    directions = [np.array([math.sin(angle), lateral * math.cos(angle)])
                  for angle in np.radians([0.0, 15.0, -15.0, 30.0, -30.0, 45.0, -45.0,
                                           60.0, -60.0])]
    for sway in np.arange(0.0, LARGEST_SWAY + 1e-9, 0.005):
        for direction in directions:
            shifted = feet_body - sway * direction
            margins = support_margins(shifted, stance, np.tile(centre, (steps, 1)))
            if np.all(margins >= REPLACEMENT_MARGIN):
                yield sway * direction


def _step(begin: float, leg: int, pose: Array, start: Array, end: Array, tables: list,
          lift: Array):
    """References of one leg's move from foot ``start`` to ``end`` (thorax frame) on an
    arc lifted by ``lift`` (3,) at mid-step, the other joints held at ``pose``."""
    samples = np.linspace(0.0, 1.0, 31)
    smooth = samples * samples * (3.0 - 2.0 * samples)
    angles = np.empty((len(samples), 3))
    previous = pose[3 * leg: 3 * leg + 3]
    for n, (fraction, along) in enumerate(zip(samples, smooth, strict=True)):
        target = start + along * (end - start) + math.sin(math.pi * fraction) * lift
        previous = solve_leg(tables[leg], target, previous).angles
        angles[n] = previous

    def references(times: np.ndarray) -> np.ndarray:
        fraction = np.clip((np.asarray(times) - begin) / STEP_TIME, 0.0, 1.0)
        rows = np.tile(pose, (len(fraction), 1))
        for k in range(3):
            rows[:, 3 * leg + k] = np.interp(fraction, samples, angles[:, k])
        return rows

    return references


def _reachable_sway(tables: list, to_body: Array, before: Array, side: list[int],
                    lateral: float, centre: Array, current: Array,
                    pose: Array) -> tuple[Array, Array]:
    """The shortest sway of :func:`_sways` at which every leg reaches its foot before its
    side's steps; returns the body's move (3,) [m, thorax frame] and the swayed pose
    (joints,) [rad]."""
    found = False
    for sway in _sways(before, side, lateral, centre):
        found = True
        shift = to_body.T @ np.array([sway[0], sway[1], 0.0])
        try:
            return shift, _pose(tables, current - shift, pose)
        except UnreachablePlanError:
            continue
    reason = "the legs cannot reach their feet at any sway that does" if found else ""
    raise UnreachablePlanError(
        f"no sway up to {LARGEST_SWAY:g} m keeps the centre of mass {REPLACEMENT_MARGIN:g} m "
        f"inside the feet left down while legs {side} are re-placed"
        + (f" ({reason})" if reason else ""))


def replacement_phases(simulation: RobotSimulation, start_pose: Array, end_pose: Array,
                       begin: float, centre: Array, name: str = "re-place",
                       body_move: Array | None = None,
                       heading: float | None = None) -> list[Phase]:
    """Phases that move the stance of ``start_pose`` into that of ``end_pose`` (module
    docstring), from simulation time ``begin`` [s].

    Parameters
    ----------
    simulation : RobotSimulation
    start_pose, end_pose : (joints,) [rad]
        The pose the feet stand in now and the pose to end in (e.g. the last pose of one
        walk and the first of the next).
    begin : float [s]
    centre : (2,) [m]
        The centre of mass in the body frame (the gait's ``com_offset``).
    name : str
        Prefix of the phases' names.
    body_move : (2,) [m], optional
        Where the body is to end, body frame x, y, from where it stands now: the new
        footholds are placed about it (default: where it stands).
    heading : float [rad], optional
        The yaw the body is to end with: when the phases begin, the new footholds are
        turned about the body by the measured yaw's error from it, so the move into the
        next pose turns the body back (a walk's end and the re-placement's own steps turn
        it by a few degrees; default: no turn).

    Raises
    ------
    UnreachablePlanError
        Where no sway keeps the centre of mass inside the three feet down, or a foot's
        new place is out of its leg's reach (checked for the footholds unturned; turned
        ones that cannot be reached are walked unturned).
    """
    plan = _Replacement(simulation, np.asarray(start_pose, float),
                        np.asarray(end_pose, float), begin, np.asarray(centre, float), name,
                        body_move, heading)
    return [Phase(phase.name, phase.duration, _Deferred(plan, k), phase.closed_loop)
            for k, phase in enumerate(plan.phases)]


class _Replacement:
    """The phases of :func:`replacement_phases`, planned for the footholds unturned and
    planned again, turned by the yaw error, when the first phase begins."""

    def __init__(self, simulation: RobotSimulation, start_pose: Array, end_pose: Array,
                 begin: float, centre: Array, name: str, body_move: Array | None,
                 heading: float | None) -> None:
        self.simulation, self.heading = simulation, heading
        self.arguments = (start_pose, end_pose, begin, centre, name, body_move)
        self.phases = _planned(simulation, *self.arguments, turn=0.0)
        self.turned = heading is None  # nothing to turn: the plan stands

    def references(self, phase: int, times: np.ndarray) -> np.ndarray:
        """Phase ``phase``'s references at ``times`` (turning the footholds first, once)."""
        if not self.turned:
            self.turned = True
            error = float(thorax_attitude(self.simulation)[2]) - self.heading
            error = math.remainder(error, 2.0 * math.pi)
            with contextlib.suppress(UnreachablePlanError):
                self.phases = _planned(self.simulation, *self.arguments, turn=-error)
        return self.phases[phase].references(times)


class _Deferred:
    """Reference function of one phase of a :class:`_Replacement`."""

    def __init__(self, plan: _Replacement, phase: int) -> None:
        self.plan, self.phase = plan, phase

    def __call__(self, times: np.ndarray) -> np.ndarray:
        return self.plan.references(self.phase, times)


def _planned(simulation: RobotSimulation, start_pose: Array, end_pose: Array, begin: float,
             centre: Array, name: str, body_move: Array | None, turn: float) -> list[Phase]:
    """The phases, the new footholds (and the body's move) turned by ``turn`` [rad] about
    the body's z axis."""
    robot = simulation.robot
    tables = [leg_dh_table(robot, leg) for leg in robot.legs]
    to_body = thorax_rotation(robot)
    feet, targets = _feet(tables, start_pose), _feet(tables, end_pose)
    targets = (to_body @ targets.T).T  # in the body frame: z is up
    targets[:, 2] = (to_body @ feet.T).T[:, 2].mean()  # on the ground the feet stand on
    if body_move is not None:  # footholds about where the body is to end
        targets[:, :2] += np.asarray(body_move, dtype=float)
    cosine, sine = math.cos(turn), math.sin(turn)
    targets[:, :2] = targets[:, :2] @ np.array([[cosine, sine], [-sine, cosine]])
    targets = (to_body.T @ targets.T).T
    lift = to_body.T @ np.array([0.0, 0.0, STEP_LIFT])
    closed = np.ones(robot.joint_count, dtype=bool)
    lateral = (to_body @ feet.T).T[:, 1]
    sides = [[leg for leg in range(len(tables)) if lateral[leg] > 0.0],
             [leg for leg in range(len(tables)) if lateral[leg] <= 0.0]]
    # rear legs first on each side, as in the lateral-sequence gait
    sides = [sorted(side, key=lambda leg: (to_body @ feet[leg])[0]) for side in sides]
    phases: list[Phase] = []
    time, pose, current = begin, start_pose, feet.copy()
    for side, direction in zip(sides, (-1.0, 1.0), strict=True):
        for leg in side:  # a sway over the three feet down, then the step
            shift, swayed = _reachable_sway(
                tables, to_body, (to_body @ current.T).T[None, :, :2], [leg], direction,
                centre, current, pose)
            phases.append(Phase(f"{name}: sway for {robot.legs[leg]}", SWAY_TIME,
                                smooth_ramp(pose, swayed, time, SWAY_TIME), closed))
            time += SWAY_TIME
            start, end = current[leg] - shift, targets[leg] - shift
            step = _step(time, leg, swayed, start, end, tables, lift)
            phases.append(Phase(f"{name}: {robot.legs[leg]}", STEP_TIME, step, closed))
            time += STEP_TIME
            pose = step(np.array([time]))[0]
            current[leg] = targets[leg]
    phases.append(Phase(f"{name}: into the next pose", SWAY_TIME,
                        smooth_ramp(pose, end_pose, time, SWAY_TIME), closed))
    return phases
