"""Heading hold for walking: the robot does not turn away from its course.

The crawl gait has no notion of yaw: the feet are placed relative to the body, so every
slide of a stance foot turns the body a little and the next footholds follow it (the flat
1 m walk turned by 13° in its first 14 s and 24° by its end). :class:`HeadingHold`
integrates the measured yaw error into a rotation ``c`` of all commanded feet about the
body's vertical axis: with the stance feet held by the ground, commanding them rotated by
``+c`` turns the body by ``−c``, and the swing feet land on the rotated pattern, so the
course is kept. The correction goes into the joint references through each leg's
Jacobian (``c`` is limited to a few degrees, well inside the linear range).

Holding the yaw does not hold the course: stance feet that slide sideways carry the body
off its line at a steady yaw (0.39–0.48 m over the 4.6 m of the 8° hill, which took the
right feet off the plate's edge). Given the gait, :class:`HeadingHold` also holds the
course: the heading it holds is biased by ``−course_gain`` times the body's cross-track
error (its distance left of the line the walk began on, the planned sway taken out;
within ±``course_limit``), so the body steers back onto its line.

A rotation of the feet turns the body once; a disturbance that turns it a little every
cycle (stance feet slipping on a slope, a turn in place whose stance turns the body by
85 % of the plan) needs a rotation that grows without end, and the correction ran into
its limit after 100 s on the 12° hill and half way through a 90° turn. Given the gait,
the rotation also leaks into a turn: every cycle the stance feet turn the body by
``−turn_leak·c`` more, as the crawl's own turn does (each foot rotated by its stance
travel, :func:`pneumaquad.gait.crawl.stance_travel`, times the turn), so a steady
disturbance is met by a steady, bounded ``c``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pneumaquad.core.jit import load_compiled
from pneumaquad.locomotion.walk import thorax_rotation
from pneumaquad.robot.kinematics import chain_workspace, stack_leg_tables
from pneumaquad.robot.legs import leg_dh_table
from pneumaquad.robot.simulation import RobotSimulation

from .course_kernels import COURSE_CROSS_TRACK, GaitTrack, cross_track_error, hold_step
from .feedback_kernels import HEADING, HEADING_SET, LAST_TIME, ROTATION

__all__ = ["HeadingHold"]


class HeadingHold:
    """Joint references that hold the heading the walk started with, one call per chunk.

    Parameters
    ----------
    simulation : RobotSimulation
        Its thorax yaw is read at every call; the first call fixes the heading to hold.
    references : callable
        ``f(times) -> (len(times), joints)`` joint references [rad] to correct.
    gain : float [1/s]
        Rate at which the yaw error [rad] is integrated into the foot rotation.
    limit : float [rad]
        Largest foot rotation.
    yaw_rate : float [rad/s]
        Rate at which the heading to hold turns (a planned turn or arc): the heading is
        the first call's yaw plus yaw_rate times the time since.
    track : GaitTrack, optional
        The plan's body path and feet travel (:func:`.course_kernels.gait_track`): hold the
        course of a straight walk too (module docstring; not with a yaw rate), and leak
        the rotation into a turn.
    course_gain : float [rad/m], course_limit : float [rad]
        Heading bias per metre of cross-track error, and its largest magnitude.
    turn_leak : float
        Body turn per cycle [rad] per radian of foot rotation (with ``track``).

    Notes
    -----
    The arithmetic of a call is one compiled call (:func:`.course_kernels.hold_step`:
    the course bias, :func:`.feedback_kernels.heading_step` and the turn leak) on arrays
    allocated here; :attr:`heading`, :attr:`rotation` and :attr:`last_time`
    are views of its state.
    """

    def __init__(self, simulation: RobotSimulation,
                 references: Callable[[np.ndarray], np.ndarray], gain: float = 0.5,
                 limit: float = math.radians(8.0), yaw_rate: float = 0.0,
                 track: GaitTrack | None = None, course_gain: float = 1.5,
                 course_limit: float = math.radians(8.0), turn_leak: float = 0.5) -> None:
        self.simulation = simulation
        self.yaw_rate = yaw_rate
        self.track = track
        self.course_gain, self.course_limit = course_gain, course_limit
        self.turn_leak = turn_leak
        legs = len(simulation.robot.legs)
        self._course = np.zeros(6)  # course_kernels.cross_track_error's state
        self._last_travel = np.zeros(legs)  # each foot's stance travel at the last call
        self._travel_state = np.zeros(1)  # 1 once _last_travel holds a call's travel
        self._no_plan = np.zeros(2)  # stands in for the plan's arrays without a track
        self.leg_turns = np.zeros(legs)  # [rad] each foot's turn from the leak
        self._start: tuple[float, float] | None = None  # (heading [rad], time [s])
        self.references = references
        self.gain = gain
        self.limit = limit
        robot = simulation.robot
        self.tables = [leg_dh_table(robot, leg) for leg in robot.legs]
        self.to_body = np.ascontiguousarray(thorax_rotation(robot))  # thorax → body frame
        self._stacked = stack_leg_tables(self.tables)
        self._workspace = chain_workspace()
        self._matrices = np.zeros((3, 3, 3))
        self._thorax_matrix = simulation.data.xmat[robot.thorax_id]  # a view, thorax → world
        self._thorax_position = simulation.data.xpos[robot.thorax_id][:2]  # a view
        self._nominal = simulation.thorax_placement
        # heading [rad], heading set (0/1), foot rotation [rad], last call's time [s]
        self._state = np.zeros(4)
        self._state[LAST_TIME] = simulation.time
        load_compiled(hold_step, *self._hold_arguments(np.zeros((1, robot.joint_count)), 0))
        if track is not None:
            load_compiled(cross_track_error, self._thorax_position, track.body[0], 0.0,
                          track.direction, self._course)

    @property
    def heading(self) -> float | None:
        """Yaw [rad] to hold; None until the first call fixes it."""
        return float(self._state[HEADING]) if self._state[HEADING_SET] else None

    @heading.setter
    def heading(self, value: float | None) -> None:
        self._state[HEADING_SET] = 0.0 if value is None else 1.0
        self._state[HEADING] = 0.0 if value is None else value

    @property
    def rotation(self) -> float:
        """Rotation [rad] of the commanded feet about the body's z axis."""
        return float(self._state[ROTATION])

    @rotation.setter
    def rotation(self, value: float) -> None:
        self._state[ROTATION] = value

    @property
    def last_time(self) -> float:
        """Simulation time [s] of the last call (of the construction before it)."""
        return float(self._state[LAST_TIME])

    @last_time.setter
    def last_time(self, value: float) -> None:
        self._state[LAST_TIME] = value

    @property
    def cross_track(self) -> float:
        """Distance [m] of the body left of its line at the last call (0 without a
        track)."""
        return float(self._course[COURSE_CROSS_TRACK])

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        rows = np.array(self.references(times), dtype=float)
        track = self.track
        index = -1 if track is None else min(max(round(
            (self.simulation.time - track.start) / track.step), 0), len(track.body) - 1)
        if self.yaw_rate != 0.0 and self._start is not None:
            heading, start = self._start
            self._state[HEADING] = heading + self.yaw_rate * (self.simulation.time - start)
        singular = hold_step(*self._hold_arguments(rows, index))
        if singular >= 0:
            raise np.linalg.LinAlgError(f"Singular matrix: the Jacobian of leg {singular}")
        if self._start is None:
            self._start = (float(self._state[HEADING]), self.last_time)
            if track is not None and self.yaw_rate == 0.0:  # the line through here
                cross_track_error(self._thorax_position, track.body[index], self._start[0],
                                  track.direction, self._course)
        return rows

    def _hold_arguments(self, rows: np.ndarray, index: int) -> tuple:
        """:func:`.course_kernels.hold_step`'s arguments: ``rows`` to correct, ``index``
        the plan sample of this call (with a track)."""
        track = self.track
        steer = track is not None and self._start is not None and self.yaw_rate == 0.0
        leak = self.turn_leak if track is not None else 0.0
        return (rows, self._thorax_matrix, self._nominal, self.to_body, self._stacked,
                self._workspace, self._matrices, self._state, self.simulation.time,
                self.gain, self.limit, steer, self._thorax_position,
                self._no_plan if track is None else track.body[index],
                0.0 if self._start is None else self._start[0],
                self._no_plan if track is None else track.direction, self._course,
                self.course_gain, self.course_limit, leak,
                self._last_travel if track is None else track.travel[index],
                self._last_travel, self.leg_turns, self._travel_state)
