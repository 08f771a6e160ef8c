"""Compiled arithmetic of the walking feedback: heading hold and swing height, per chunk.

:class:`.heading_control.HeadingHold` and :class:`.swing_control.SwingHeightCorrection`
run once per control chunk (10 ms); what they compute from the simulation's state is here
as compiled functions on arrays the controllers allocate once: MuJoCo's own arrays (views
of ``MjData``), the legs' stacked DH tables (:class:`pneumaquad.robot.kinematics.LegTables`)
and a :class:`pneumaquad.robot.kinematics.ChainWorkspace` of scratch. The correction of the
joint references is made in place on the chunk's rows, each leg through its Jacobian at
the chunk's middle row (:func:`pneumaquad.robot.legs.add_leg_step`), so a chunk costs no
Python loop and no allocation. The gait's timing (:func:`pneumaquad.gait.crawl.leg_phases`,
the lift of :func:`pneumaquad.gait.crawl.foot_positions_ground`) is repeated here as
scalar functions of one leg and one instant, with the same arithmetic.

Units: SI and radians; the thorax frame of the DH tables for joint steps and foot shifts.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from pneumaquad.core.jit import compiled
from pneumaquad.gait.crawl import _PHASE_TOLERANCE, CrawlGait, gait_offsets
from pneumaquad.robot.kinematics import ChainWorkspace, LegTables
from pneumaquad.robot.legs import add_leg_step, middle_leg_chain

__all__ = ["HEADING", "HEADING_SET", "LAST_TIME", "ROTATION", "GaitTiming", "gait_timing",
           "heading_step", "leg_phase", "planned_lift", "remainder", "swing_step",
           "thorax_yaw", "turn_leg"]

Array = NDArray[np.float64]

#: Slots of :class:`.heading_control.HeadingHold`'s state array (4,).
HEADING, HEADING_SET, ROTATION, LAST_TIME = 0, 1, 2, 3


class GaitTiming(NamedTuple):
    """What the compiled feedback needs of a :class:`pneumaquad.gait.crawl.CrawlGait`."""

    period: float  # [s] gait cycle
    duty_factor: float  # stance fraction β
    step_height: float  # [m] foot lift at mid-swing
    lift_fraction: float  # swing fraction at each end spent only lifting or lowering
    phase_tolerance: float  # [cycle] a touching-down foot counts as stance this early
    offsets: Array  # (legs,) lift-off of each leg [cycle fraction]


def gait_timing(gait: CrawlGait) -> GaitTiming:
    """The :class:`GaitTiming` of ``gait`` (its lift-off offsets as the gait computes
    them)."""
    offsets = gait_offsets(gait)
    return GaitTiming(float(gait.period), float(gait.duty_factor), float(gait.step_height),
                      float(gait.lift_fraction), float(_PHASE_TOLERANCE),
                      np.ascontiguousarray(offsets, dtype=float))


@compiled
def leg_phase(timing: GaitTiming, gait_time: float, leg: int) -> float:
    """Phase in [0, 1) of ``leg`` since its lift-off at ``gait_time`` [s] (compiled
    :func:`pneumaquad.gait.crawl.leg_phases` of one leg and instant)."""
    cycles = gait_time / timing.period - timing.offsets[leg]
    return cycles - math.floor(cycles)


@compiled
def planned_lift(timing: GaitTiming, phase: float) -> float:
    """Planned foot height [m] above the ground of a leg at ``phase`` (compiled: the z of
    :func:`pneumaquad.gait.crawl.foot_positions_ground`, same arithmetic)."""
    swing = 1.0 - timing.duty_factor
    if not phase < swing:
        return 0.0
    progress = min(max(phase / swing, 0.0), 1.0)
    edge = timing.lift_fraction
    if edge > 0.0:  # rise over the edge, stay up, lower over the last edge
        ramp = min(max(min(progress, 1.0 - progress) / edge, 0.0), 1.0)
        height = 0.5 * (1.0 - math.cos(math.pi * ramp))
    else:
        height = 0.5 * (1.0 - math.cos(2.0 * math.pi * progress))
    return timing.step_height * height


@compiled
def remainder(dividend: float, divisor: float) -> float:
    """IEEE remainder ``dividend − n·divisor`` [units of both], n the integer nearest the
    exact quotient, ties to even (:func:`math.remainder`, compiled), for ``divisor`` > 0
    and quotients of at most 2 in magnitude (there every step is exact)."""
    quotient = dividend / divisor
    nearest = math.floor(quotient)
    if quotient - nearest >= 0.5:
        nearest += 1.0
    rest = dividend - nearest * divisor
    half = 0.5 * divisor
    if rest > half or (rest == half and nearest % 2.0 != 0.0):
        rest -= divisor
    elif rest < -half or (rest == -half and nearest % 2.0 != 0.0):
        rest += divisor
    if rest == 0.0:
        rest = math.copysign(0.0, dividend)
    return rest


@compiled
def thorax_yaw(thorax_matrix: Array, nominal: Array) -> float:
    """Yaw [rad] of the thorax relative to its nominal placement (compiled: the yaw of
    :func:`pneumaquad.robot.recording.thorax_attitude`).

    ``thorax_matrix`` (9,) is MuJoCo's ``xmat`` row of the thorax (thorax → world, row
    major), ``nominal`` (3, 3) the nominal placement's rotation.
    """
    first = (thorax_matrix[0] * nominal[0, 0] + thorax_matrix[1] * nominal[0, 1]
             + thorax_matrix[2] * nominal[0, 2])
    second = (thorax_matrix[3] * nominal[0, 0] + thorax_matrix[4] * nominal[0, 1]
              + thorax_matrix[5] * nominal[0, 2])
    return math.atan2(second, first)


@compiled
def heading_step(rows: Array, thorax_matrix: Array, nominal: Array, to_body: Array,
                 tables: LegTables, workspace: ChainWorkspace, matrices: Array, state: Array,
                 time: float, gain: float, limit: float) -> int:
    """One chunk of :class:`.heading_control.HeadingHold`, in place (compiled).

    Parameters
    ----------
    rows : (n, 3·legs) [rad]
        The chunk's joint references, corrected in place.
    thorax_matrix, nominal
        As for :func:`thorax_yaw`.
    to_body : (3, 3)
        Thorax → body frame rotation.
    tables, workspace
        The legs' :class:`~pneumaquad.robot.kinematics.LegTables` and a
        :class:`~pneumaquad.robot.kinematics.ChainWorkspace`.
    matrices : (3, 3, 3)
        Scratch: the turn about the body's z axis, a product, the turn in the thorax frame.
    state : (4,)
        Heading [rad], whether it is set (0/1), foot rotation [rad], time of the last
        call [s] (slots :data:`HEADING`, :data:`HEADING_SET`, :data:`ROTATION`,
        :data:`LAST_TIME`), updated.
    time : float [s]
        Simulation time.
    gain : float [1/s], limit : float [rad]
        Integration rate of the yaw error and largest foot rotation.

    Returns
    -------
    int
        -1, or the leg whose Jacobian is singular (``rows`` then partly corrected).
    """
    yaw = thorax_yaw(thorax_matrix, nominal)
    if state[HEADING_SET] == 0.0:
        state[HEADING] = yaw
        state[HEADING_SET] = 1.0
    error = remainder(yaw - state[HEADING], 2.0 * math.pi)
    interval = time - state[LAST_TIME]
    state[LAST_TIME] = time
    rotation = state[ROTATION] + gain * error * interval
    if rotation < -limit:
        rotation = -limit
    if rotation > limit:
        rotation = limit
    state[ROTATION] = rotation
    if rotation == 0.0:
        return -1
    for leg in range(tables.d.shape[0]):
        if not turn_leg(rows, leg, rotation, to_body, tables, workspace, matrices):
            return leg
    return -1


@compiled
def turn_leg(rows: Array, leg: int, angle: float, to_body: Array, tables: LegTables,
             workspace: ChainWorkspace, matrices: Array) -> bool:
    """Turn ``leg``'s commanded foot by ``angle`` [rad] about the body's z axis through
    the body origin, on ``rows`` (n, 3·legs) [rad] in place, through its Jacobian at the
    middle row (compiled). ``to_body`` (3, 3) thorax → body frame; ``matrices`` (3, 3, 3)
    scratch. Returns False where the Jacobian is singular."""
    turn, product, turn_thorax = matrices[0], matrices[1], matrices[2]
    cos, sin = math.cos(angle), math.sin(angle)
    turn[0, 0], turn[0, 1], turn[0, 2] = cos, -sin, 0.0
    turn[1, 0], turn[1, 1], turn[1, 2] = sin, cos, 0.0
    turn[2, 0], turn[2, 1], turn[2, 2] = 0.0, 0.0, 1.0
    for r in range(3):  # to_bodyᵀ · turn · to_body, left to right
        for c in range(3):
            product[r, c] = (to_body[0, r] * turn[0, c] + to_body[1, r] * turn[1, c]
                             + to_body[2, r] * turn[2, c])
    for r in range(3):
        for c in range(3):
            turn_thorax[r, c] = (product[r, 0] * to_body[0, c] + product[r, 1] * to_body[1, c]
                                 + product[r, 2] * to_body[2, c])
    foot, shift = workspace.foot, workspace.shift
    middle_leg_chain(rows, tables, leg, workspace)
    for r in range(3):
        shift[r] = (foot[0] * turn_thorax[r, 0] + foot[1] * turn_thorax[r, 1]
                    + foot[2] * turn_thorax[r, 2]) - foot[r]
    if shift[0] == 0.0 and shift[1] == 0.0 and shift[2] == 0.0:
        return True
    return add_leg_step(rows, leg, shift, workspace)


@compiled
def swing_step(rows: Array, gait_time: float, time: float, thorax_matrix: Array,
               thorax_position: Array, site_positions: Array, foot_sites: NDArray[np.int64],
               timing: GaitTiming, lift_off_height: Array, was_stance: NDArray[np.bool_],
               correction: Array, clock: Array, limit: float, fade: float,
               tables: LegTables, workspace: ChainWorkspace) -> int:
    """One chunk of :class:`.swing_control.SwingHeightCorrection`, in place (compiled).

    Parameters
    ----------
    rows : (n, 3·legs) [rad]
        The chunk's joint references, corrected in place.
    gait_time : float [s]
        Gait time of the chunk's middle row.
    time : float [s]
        Simulation time.
    thorax_matrix : (9,)
        MuJoCo's ``xmat`` row of the thorax (thorax → world, row major).
    thorax_position : (3,) [m]
        MuJoCo's ``xpos`` row of the thorax.
    site_positions : (sites, 3) [m], foot_sites : (legs,)
        MuJoCo's ``site_xpos`` and the feet's site ids.
    timing : GaitTiming
    lift_off_height : (legs,) [m], was_stance : (legs,) bool, correction : (legs,) [m]
        World height of each foot at its last lift-off, stance at the last call, present
        correction (world z); updated.
    clock : (1,) [s]
        Time of the last call, updated.
    limit : float [m], fade : float [s]
        Largest correction and time constant of its fade after touchdown.
    tables, workspace
        The legs' :class:`~pneumaquad.robot.kinematics.LegTables` and a
        :class:`~pneumaquad.robot.kinematics.ChainWorkspace`.

    Returns
    -------
    int
        -1, or the leg whose Jacobian is singular (``rows`` then partly corrected).
    """
    legs = foot_sites.shape[0]
    touchdown = 1.0 - timing.duty_factor - timing.phase_tolerance
    interval = time - clock[0]
    clock[0] = time
    height_base = thorax_position[2]
    foot, shift = workspace.foot, workspace.shift
    for leg in range(legs):
        phase = leg_phase(timing, gait_time, leg)
        stance = phase >= touchdown
        if was_stance[leg] and not stance:
            lift_off_height[leg] = site_positions[foot_sites[leg], 2]
        was_stance[leg] = stance
        if stance:
            correction[leg] *= math.exp(-interval / fade)
            if correction[leg] != 0.0:
                middle_leg_chain(rows, tables, leg, workspace)
        else:
            middle_leg_chain(rows, tables, leg, workspace)
            lift = planned_lift(timing, phase)
            height = height_base + (thorax_matrix[6] * foot[0] + thorax_matrix[7] * foot[1]
                                    + thorax_matrix[8] * foot[2])  # world z [m]
            # weighted by the planned lift, so the correction vanishes at lift-off and
            # touchdown: the foot lands where planned, with no step in the reference
            weight = lift / timing.step_height if timing.step_height != 0.0 else 0.0
            error = lift_off_height[leg] + lift - height
            correction[leg] = weight * min(max(error, -limit), limit)
        for k in range(3):  # the world z correction in the thorax frame
            shift[k] = correction[leg] * thorax_matrix[6 + k]
        moved = shift[0] != 0.0 or shift[1] != 0.0 or shift[2] != 0.0
        if moved and not add_leg_step(rows, leg, shift, workspace):
            return leg
    return -1
