"""Compiled arithmetic of the course hold, the turn leak and the slope placement, per chunk.

:class:`.heading_control.HeadingHold` (course and turn leak) and
:class:`.body_placement.BodyPlacement` run once per control chunk; what they compute is
here as compiled functions on arrays they allocate once, as in :mod:`.feedback_kernels`.
What they need of the plan — the planned body position and each foot's stance travel —
is tabulated once per walk (:func:`gait_track`) and read by index, so the gait's
arithmetic stays in :mod:`pneumaquad.gait.crawl` alone.

Units: SI and radians; world frame for positions, the thorax frame of the DH tables for
foot shifts.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from pneumaquad.core.jit import compiled
from pneumaquad.gait.crawl import CrawlGait, body_positions, stance_travel
from pneumaquad.robot.kinematics import ChainWorkspace, LegTables, solve_3x3
from pneumaquad.robot.legs import shift_feet_into

from .feedback_kernels import HEADING, ROTATION, GaitTiming, heading_step, leg_phase, turn_leg

__all__ = ["COURSE_CROSS_TRACK", "COURSE_SET", "GaitTrack", "cross_track_error",
           "gait_track", "hold_step", "leak_into_turn", "placement_step"]

Array = NDArray[np.float64]

#: Slots of the course state (6,): origin x, y [m], left normal x, y, set (0/1),
#: last cross-track error [m].
COURSE_SET, COURSE_CROSS_TRACK = 4, 5


class GaitTrack(NamedTuple):
    """The plan's body path and feet travel, tabulated for the compiled feedback."""

    start: float  # [s] simulation time of the gait's time 0
    step: float  # [s] interval of the table
    body: Array  # (n, 2) [m] planned body position in the gait's ground frame
    travel: Array  # (n, legs) each foot's stance travel (gait.crawl.stance_travel)
    direction: Array  # (2,) unit direction of travel in the body frame


def gait_track(gait: CrawlGait, start: float, duration: float,
               step: float = 0.01) -> GaitTrack:
    """:class:`GaitTrack` of ``gait`` from simulation time ``start`` [s] for ``duration``
    [s] (and one step beyond), every ``step`` [s] (the control chunk)."""
    times = np.arange(0.0, duration + 2.0 * step, step)
    return GaitTrack(float(start), float(step),
                     np.ascontiguousarray(body_positions(gait, times)),
                     np.ascontiguousarray(stance_travel(gait, times)),
                     np.ascontiguousarray(gait.direction, dtype=float))


@compiled
def cross_track_error(position: Array, planned: Array, yaw: float, direction: Array,
                      state: Array) -> float:
    """Distance [m] of the body left of its line (compiled).

    ``position`` (2,) [m] the thorax's world x, y; ``planned`` (2,) [m] its planned
    position (gait ground frame, :attr:`GaitTrack.body`); ``yaw`` [rad] the yaw the walk
    began with (the ground frame → world turn); ``direction`` (2,) the travel direction in
    the body frame. The first call (``state[COURSE_SET]`` 0) fixes the line through the
    body, along the travel; the error is then the offset, the planned sway taken out,
    along the line's left normal. ``state`` (6,) is updated.
    """
    cosine, sine = math.cos(yaw), math.sin(yaw)
    x = position[0] - (cosine * planned[0] - sine * planned[1])
    y = position[1] - (sine * planned[0] + cosine * planned[1])
    if state[COURSE_SET] == 0.0:
        along_x = cosine * direction[0] - sine * direction[1]
        along_y = sine * direction[0] + cosine * direction[1]
        state[0], state[1], state[2], state[3] = x, y, -along_y, along_x
        state[COURSE_SET] = 1.0
    error = (x - state[0]) * state[2] + (y - state[1]) * state[3]
    state[COURSE_CROSS_TRACK] = error
    return error


@compiled
def leak_into_turn(rows: Array, travel: Array, last_travel: Array, has_last: bool,
                   rotation: float, leak: float, leg_turns: Array, to_body: Array,
                   tables: LegTables, workspace: ChainWorkspace, matrices: Array) -> int:
    """One chunk of the turn leak (compiled): each foot's turn (``leg_turns`` (legs,)
    [rad], updated) grows by ``−leak·rotation`` times the change of its stance travel
    (``travel`` now, ``last_travel`` at the last call, when ``has_last``), and every foot
    is turned by it (:func:`turn_leg`). Returns -1, or the leg whose Jacobian is
    singular."""
    for leg in range(travel.shape[0]):
        if has_last:
            leg_turns[leg] += -leak * rotation * (travel[leg] - last_travel[leg])
        if leg_turns[leg] != 0.0 and not turn_leg(rows, leg, leg_turns[leg], to_body,
                                                  tables, workspace, matrices):
            return leg
    return -1


@compiled
def hold_step(rows: Array, thorax_matrix: Array, nominal: Array, to_body: Array,
              tables: LegTables, workspace: ChainWorkspace, matrices: Array, state: Array,
              time: float, gain: float, limit: float, steer: bool, position: Array,
              planned: Array, start_yaw: float, direction: Array, course: Array,
              course_gain: float, course_limit: float, leak: float, travel: Array,
              last_travel: Array, leg_turns: Array, travel_state: Array) -> int:
    """One chunk of :class:`.heading_control.HeadingHold` in one compiled call: with
    ``steer``, the heading held (``state[HEADING]``) is ``start_yaw`` less the course
    bias, ``course_gain`` times the cross-track error (:func:`cross_track_error`) within
    ±``course_limit``; then :func:`.feedback_kernels.heading_step`; then, with ``leak``
    > 0, :func:`leak_into_turn` from the feet's stance ``travel`` now (``last_travel`` and
    ``travel_state[0]`` (set 0/1) updated). Returns -1, or the leg whose Jacobian is
    singular."""
    if steer:
        error = cross_track_error(position, planned, start_yaw, direction, course)
        bias = min(max(course_gain * error, -course_limit), course_limit)
        state[HEADING] = start_yaw - bias
    singular = heading_step(rows, thorax_matrix, nominal, to_body, tables, workspace,
                            matrices, state, time, gain, limit)
    if singular < 0 and leak > 0.0:
        singular = leak_into_turn(rows, travel, last_travel, travel_state[0] != 0.0,
                                  state[ROTATION], leak, leg_turns, to_body, tables,
                                  workspace, matrices)
        last_travel[:] = travel
        travel_state[0] = 1.0
    return singular


@compiled
def placement_step(rows: Array, gait_time: float, timing: GaitTiming, site_positions: Array,
                   foot_sites: NDArray[np.int64], centre: Array, thorax_matrix: Array,
                   uphill: Array, blend: float, limit: float, level: float, scratch: Array,
                   shifts: Array, tables: LegTables, workspace: ChainWorkspace) -> int:
    """One chunk of :class:`.body_placement.BodyPlacement`, in place (compiled).

    The least-squares plane z = a + b·x + c·y through the feet the gait has in stance at
    ``gait_time`` [s] (all of them before the gait starts; skipped with fewer than three
    or a singular fit), its unit normal n, the centre of mass's height h = (c − f̄)·n over
    it (``centre`` (3,) [m], f̄ the feet's mean), the offset h·(ẑ/(ẑ·n) − n) (limited to
    ``limit`` [m]; zero on a plane tilted less than ``level`` [rad], ground taken as
    level) blended into ``uphill`` (3,) [m, world] by ``blend``; every foot then
    shifted by −``uphill`` (thorax frame through ``thorax_matrix`` (9,), thorax → world
    row major). ``scratch`` (3, 3 + 1 + 3 + 4): normal equations, right side, solution,
    elimination. Returns -1, or the leg whose Jacobian is singular.
    """
    legs = foot_sites.shape[0]
    normal_matrix = scratch[:, 0:3]
    right = scratch[:, 3]
    solution = scratch[:, 4]
    elimination = scratch[:, 5:9]
    normal_matrix[:, :] = 0.0
    right[:] = 0.0
    mean_x = mean_y = mean_z = 0.0
    count = 0
    swing = 1.0 - timing.duty_factor
    for leg in range(legs):
        if gait_time >= 0.0 and leg_phase(timing, gait_time, leg) < swing:
            continue
        x = site_positions[foot_sites[leg], 0]
        y = site_positions[foot_sites[leg], 1]
        z = site_positions[foot_sites[leg], 2]
        row = (1.0, x, y)
        for r in range(3):
            right[r] += row[r] * z
            for c in range(3):
                normal_matrix[r, c] += row[r] * row[c]
        mean_x += x
        mean_y += y
        mean_z += z
        count += 1
    if count >= 3 and solve_3x3(normal_matrix, right, elimination, solution):
        norm = math.sqrt(solution[1] ** 2 + solution[2] ** 2 + 1.0)
        nx, ny, nz = -solution[1] / norm, -solution[2] / norm, 1.0 / norm
        height = ((centre[0] - mean_x / count) * nx + (centre[1] - mean_y / count) * ny
                  + (centre[2] - mean_z / count) * nz)
        if nz > math.cos(level):  # level ground: the feet's heights differ by contact
            height = 0.0
        target_x, target_y, target_z = -height * nx, -height * ny, height * (1.0 / nz - nz)
        length = math.sqrt(target_x ** 2 + target_y ** 2 + target_z ** 2)
        scale = limit / length if length > limit else 1.0
        uphill[0] += blend * (scale * target_x - uphill[0])
        uphill[1] += blend * (scale * target_y - uphill[1])
        uphill[2] += blend * (scale * target_z - uphill[2])
    for k in range(3):  # −uphill in the thorax frame: xmatᵀ · (−uphill)
        value = -(thorax_matrix[k] * uphill[0] + thorax_matrix[3 + k] * uphill[1]
                  + thorax_matrix[6 + k] * uphill[2])
        for leg in range(legs):
            shifts[leg, k] = value
    return shift_feet_into(rows, tables, shifts, workspace)
