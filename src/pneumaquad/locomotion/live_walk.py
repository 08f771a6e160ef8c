"""The walk of ``pneumaquad robot walk``, commanded live: speed and heading change while
it runs (the operator console's automatic mode).

:class:`LiveWalk` plays the same phases as a walk of the command line on a running
simulation, one control chunk at a time: the omnidirectional crawl of
:func:`.walking.planned_walk` (start-up cycle, transfer gap, sway to the planned margin,
the posture and cycle the legs reach, :func:`.walking.reachable_plan`) with the feedback
of :func:`.walking.walk_phase` (force-controlled stance, swing height from the ground,
body placement on slopes, heading and course hold) and its gate, a verified stance.
Nothing of the walk is specific to live driving except when its walks begin and end:

* a command with a speed or a yaw rate starts a walk of :attr:`LiveWalk.cycles` gait
  cycles at that speed and heading (counter-clockwise from the body's forward axis when
  the walk begins; each walk holds the yaw it begins with, or turns from it at the yaw
  rate: an arc, or at speed 0 a turn in place); where the legs cannot reach the command,
  the largest share of it they reach (speed and yaw rate scaled together, in steps of a
  fifth) is walked and said;
* a new command takes effect at the end of the gait cycle in progress, where the walk's
  four feet are down (the instant of a lift-off): speed 0 stands there, in the walk's
  pose, under the walk's force-controlled stance (:class:`.stance_control.StanceSettle`);
  the same speed and heading again resumes that walk where it stopped; another walk
  begins after its feet are re-placed, one at a time, from where the last cycle left
  them (:func:`.replacement.replacement_phases`, the body turned back to the walking
  frame's yaw: the yaw walking began with, or the one the last turn left), the legs have
  shed their internal forces
  (:func:`.walking.settled_hold`) and its stance is verified;
* where only the body has to move between two stances (every foot within
  :data:`IN_PLACE` of its foothold: the first walk from the standing pose, straight or
  backwards), the body shifts there in :data:`SHIFT_TIME` instead;
* a walk that runs its cycles out with the command unchanged goes on with its next
  cycles (its steady cycles repeat).

A stance that is not verified stops the walking where it stands; the reason is kept in
:attr:`LiveWalk.message`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from pneumaquad.gait.crawl import CrawlGait, body_sway
from pneumaquad.robot.experiment import Phase, reference_table
from pneumaquad.robot.recording import thorax_attitude
from pneumaquad.robot.simulation import RobotSimulation
from pneumaquad.robot.stand_up import smooth_ramp

from .reach import UnreachablePlanError
from .replacement import foothold_moves, replacement_phases
from .stance_control import StanceSettle
from .walk import WalkPlan
from .walk_settings import WalkSettings
from .walking import planned_walk, reachable_plan, stance_hold, walk_phase

__all__ = ["IN_PLACE", "SHIFT_TIME", "LiveWalk"]

Array = NDArray[np.float64]

#: Largest move [m] of every foot between two stances that the body's shift alone makes
#: (the feet are then not re-placed).
IN_PLACE = 0.01
#: Duration [s] of the body's shift between two stances with the feet in place.
SHIFT_TIME = 1.0
#: Speeds tried, as fractions of the one commanded, where the legs cannot reach it.
SPEED_SCALES = (1.0, 0.8, 0.6, 0.4, 0.2)
#: The name of the phase of standing still between walks.
STAND = "standing"


@dataclass
class _Scheduled:
    """A phase at its start time [s] on the simulation's clock; the walk it plays, if
    it is a walk phase."""

    start: float
    phase: Phase
    walk: _Walk | None = None

    @property
    def end(self) -> float:
        return self.start + self.phase.duration


@dataclass(frozen=True)
class _Walk:
    """One walk of the schedule: its command, settings, gait, plan and start [s]."""

    command: tuple[float, float, float]  # speed [m/s], heading [rad], yaw rate [rad/s]
    settings: WalkSettings
    gait: CrawlGait
    plan: WalkPlan
    start: float

    @property
    def turns(self) -> bool:
        """The walk turns the body (a turn in place or an arc)."""
        return self.settings.body_yaw_rate() != 0.0

    @cached_property
    def lift_offs(self) -> Array:
        """Simulation times [s] of the plan's lift-offs."""
        stance = self.plan.stance
        before = np.vstack([np.ones_like(stance[:1]), stance[:-1]])  # four feet down before
        return self.start + self.plan.times[np.any(before & ~stance, axis=1)]

    def index(self, time: float) -> int:
        """The plan's row at simulation ``time`` [s] (clipped into the plan)."""
        step = float(self.plan.times[1] - self.plan.times[0])
        return min(max(round((time - self.start) / step), 0), len(self.plan.references) - 1)

    def sway(self, time: float) -> Array:
        """The planned sway (2,) [m, body frame] at simulation ``time`` [s]."""
        return body_sway(self.gait, np.array([time - self.start]))[0]

    def pose(self, time: float) -> Array:
        """The planned pose (joints,) [rad] at simulation ``time`` [s]."""
        return self.plan.references[self.index(time)]


@dataclass
class _Rest:
    """Where the schedule leaves the robot: its pose [rad], its body's sway from the
    stance's centre [m, body frame], and the walk (and that walk's time [s]) it stands
    in, if any."""

    pose: Array
    sway: Array = field(default_factory=lambda: np.zeros(2))
    walk: _Walk | None = None
    walk_time: float = 0.0


class LiveWalk:
    """The command line's walk, commanded live (module docstring).

    Parameters
    ----------
    simulation : RobotSimulation
        The free quadruped standing in its standing pose (its present joint references).
    settings : WalkSettings, optional
        Everything but the speed, heading, yaw rate, turn and distance (the defaults of
        ``robot walk``).
    cycles : int
        Gait cycles of each walk.
    """

    def __init__(self, simulation: RobotSimulation, settings: WalkSettings | None = None,
                 cycles: int = 20) -> None:
        self.simulation = simulation
        self.settings = settings or WalkSettings()
        self.cycles = cycles
        standing = simulation.reference_angles.copy()
        #: The yaw [rad] of the walking frame: the thorax's when the walking began, or
        #: when the last turn ended.
        self.yaw = float(thorax_attitude(simulation)[2])
        self.speed, self.heading, self.yaw_rate = 0.0, 0.0, 0.0
        self._turned = False  # a turning walk ran since the walking frame was measured
        self.schedule: list[_Scheduled] = []
        self.rest = _Rest(standing)
        self.message = ""
        self.walks = 0
        self._entered: _Scheduled | None = None
        self._steps_before = 0  # feet lifted by walks dropped from the schedule

    # --- commands --------------------------------------------------------------------
    def command(self, speed: float, heading: float, yaw_rate: float = 0.0) -> None:
        """Walk at ``speed`` [m/s] along ``heading`` [rad] (the body's frame when the walk
        begins; a negative speed walks the other way) while the body turns at
        ``yaw_rate`` [rad/s] (counter-clockwise: an arc, or with speed 0 a turn in place),
        or stand (both 0), from the end of the cycle in progress."""
        if speed < 0.0:
            speed, heading = -speed, heading + math.pi
        heading = math.remainder(heading, 2.0 * math.pi)
        if speed == 0.0:
            heading = self.heading
        if (speed, heading, yaw_rate) == self._command:
            return
        self.speed, self.heading, self.yaw_rate = float(speed), float(heading), float(yaw_rate)
        now = self.simulation.time
        current = self._current(now)
        if current is None:  # standing, or at the end of the schedule
            self._extend(now)
        elif current.walk is not None:  # cut the walk at the end of this cycle
            walk = current.walk
            period = walk.settings.period
            cut = walk.start + period * math.ceil((now - walk.start) / period - 1e-9)
            cut = min(cut, current.end)
            current.phase.duration = cut - current.start
            self.schedule = self.schedule[: self.schedule.index(current) + 1]
            self.rest = _Rest(walk.pose(cut), walk.sway(cut), walk,
                              cut - walk.start)
            self._extend(cut)
        # in a transition, the walk it leads to is checked against the command when it
        # begins (:meth:`_enter`)

    @property
    def _command(self) -> tuple[float, float, float]:
        return (self.speed, self.heading, self.yaw_rate)

    @property
    def moving(self) -> bool:
        """The command asks to walk or turn."""
        return self.speed != 0.0 or self.yaw_rate != 0.0

    @property
    def walking(self) -> bool:
        """A walk phase is running now."""
        current = self._current(self.simulation.time)
        return current is not None and current.walk is not None

    @property
    def phase_name(self) -> str:
        """The name of the phase running now ("" when standing)."""
        current = self._current(self.simulation.time)
        return "" if current is None else current.phase.name

    @property
    def current_walk(self) -> _Walk | None:
        """The walk running now, if any."""
        current = self._current(self.simulation.time)
        return None if current is None else current.walk

    def steps_taken(self) -> int:
        """Feet lifted so far, every walk of the schedule counted (each over the time it
        runs: a resumed walk from where it resumed, a cut one up to its cut)."""
        now = self.simulation.time
        lifted = 0
        for entry in self.schedule:
            if entry.walk is not None and entry.start <= now:
                lifts = entry.walk.lift_offs
                lifted += int(np.count_nonzero((lifts >= entry.start)
                                               & (lifts < min(now, entry.end))))
        return lifted + self._steps_before

    def planned_stance(self) -> NDArray[np.bool_] | None:
        """(legs,) the feet the walk running now holds down; None when not walking."""
        walk = self.current_walk
        return None if walk is None else walk.plan.stance[walk.index(self.simulation.time)]

    def planned_margin(self) -> float:
        """The walk's planned static margin [m] now (NaN when not walking)."""
        walk = self.current_walk
        return math.nan if walk is None else float(
            walk.plan.margins[walk.index(self.simulation.time)])

    # --- scheduling ------------------------------------------------------------------
    def _current(self, now: float) -> _Scheduled | None:
        step = self.simulation.control_step
        for entry in self.schedule:
            if entry.start - 0.5 * step <= now < entry.end - 0.5 * step:
                return entry
        return None

    def _extend(self, begin: float) -> None:
        """Schedule, from ``begin`` [s] and :attr:`rest`, the walk the command asks (none
        when it asks neither speed nor turn: the robot stands where the schedule leaves
        it)."""
        if not self.moving:
            return
        rest = self.rest
        if rest.walk is not None and rest.walk.command == self._command:
            walk = rest.walk  # resume it: from its steady cycle's start after the first
            self._append_walk(walk.settings, walk.gait, walk.plan, begin,
                              walk.settings.period if rest.walk_time > 0.5 * walk.settings.period
                              else 0.0)
            return
        try:
            settings, gait, plan = self._plan()
        except (UnreachablePlanError, ValueError) as error:
            self.message = f"cannot walk {self._described()}: {error}"
            self.speed = self.yaw_rate = 0.0
            return
        begin = self._append_transition(begin, plan.references[0],
                                        body_sway(gait, np.array([0.0]))[0], gait)
        self._append_walk(settings, gait, plan, begin)

    def _append_walk(self, settings: WalkSettings, gait: CrawlGait, plan: WalkPlan,
                     begin: float, walk_time: float = 0.0) -> None:
        """Schedule the walk of ``plan`` from ``begin`` [s], from its time ``walk_time``
        [s] on (0: its start, gated by a verified stance; a cycle boundary: resumed)."""
        start = begin - walk_time
        walk = _Walk(self._command, settings, gait, plan, start)
        phase = walk_phase(self.simulation, settings, gait, plan, start,
                           name=f"walk {self.walks + 1}")
        if walk_time:
            phase = replace(phase, duration=phase.duration - walk_time, gate=None)
        self.schedule.append(_Scheduled(begin, phase, walk))
        self.walks += 1
        end = begin + phase.duration
        self.rest = _Rest(walk.pose(end), walk.sway(end), walk,
                          end - start)

    def _plan(self) -> tuple[WalkSettings, CrawlGait, WalkPlan]:
        """The walk of the command: its settings, gait and plan (at the fastest speed and
        yaw rate, scaled together by :data:`SPEED_SCALES`, that the legs reach)."""
        robot = self.simulation.robot
        period = self.settings.period
        error: Exception = UnreachablePlanError("no speed reaches")
        for scale in SPEED_SCALES:
            speed, rate = self.speed * scale, self.yaw_rate * scale
            if speed == 0.0:  # a turn in place by the cycles' turn
                asked = replace(self.settings, heading=0.0, yaw_rate=rate,
                                turn=rate * period * self.cycles)
            else:
                asked = replace(self.settings, speed=speed, heading=self.heading,
                                yaw_rate=rate, distance=speed * period * self.cycles)
            settings, posture = reachable_plan(robot, asked)
            if posture is None:
                continue
            if speed == 0.0:  # whole cycles of the period chosen, at the rate asked
                settings = replace(settings, turn=rate * settings.period * self.cycles)
            try:
                gait, plan, _ = planned_walk(robot, settings, posture)
            except (UnreachablePlanError, ValueError) as reason:
                error = reason
                continue
            self.message = ("" if scale == 1.0 else
                            f"{scale:.0%} of the command: the most the legs reach "
                            f"({self._described()})")
            return settings, gait, plan
        raise error

    def _described(self) -> str:
        """The command in words."""
        words = []
        if self.speed:
            words.append(f"{1000 * self.speed:.0f} mm/s at heading "
                         f"{math.degrees(self.heading):.0f}°")
        if self.yaw_rate:
            words.append(f"turning {math.degrees(self.yaw_rate):+.1f}°/s")
        return ", ".join(words)

    def _append_transition(self, begin: float, end_pose: Array, body_sway_after: Array,
                           gait: CrawlGait) -> float:
        """Schedule the move from :attr:`rest` into the first pose ``end_pose`` of the
        walk of ``gait`` (its body swayed by ``body_sway_after`` [m]); returns when it
        ends [s]."""
        rest = self.rest
        body_move = np.asarray(body_sway_after) - rest.sway
        closed = np.ones(self.simulation.robot.joint_count, dtype=bool)
        moves = foothold_moves(self.simulation, rest.pose, end_pose, body_move)
        if np.all(moves < IN_PLACE):
            phases = [Phase("shift", SHIFT_TIME,
                            smooth_ramp(rest.pose, end_pose, begin, SHIFT_TIME), closed)]
        else:
            # after a turn, the body keeps the yaw it turned to (the walking frame is
            # measured again when the re-placement begins)
            turned = rest.walk is not None and rest.walk.turns
            phases = replacement_phases(self.simulation, rest.pose, end_pose, begin,
                                        gait.com_offset, "re-place", body_move=body_move,
                                        heading=None if turned else self.yaw)
            phases += stance_hold(self.simulation, end_pose, self.settings)
        for phase in phases:
            self.schedule.append(_Scheduled(begin, phase))
            begin += phase.duration
        self.rest = _Rest(np.asarray(end_pose, dtype=float).copy(),
                          np.asarray(body_sway_after, dtype=float).copy())
        return begin

    # --- stepping --------------------------------------------------------------------
    def step(self, count: int) -> None:
        """Advance the simulation ``count`` control steps, the references of the phases
        evaluated once per recording chunk (``simulation.recording_every`` steps, as a
        command-line walk's)."""
        simulation = self.simulation
        every = simulation.robot.parameters.simulation.recording_every
        step = simulation.control_step
        joints = simulation.robot.joint_count
        while count > 0:
            now = simulation.time
            entry = self._current(now)
            if entry is not None and entry is not self._entered:
                entry = self._enter(entry)
            if entry is None:
                if self.schedule:  # the schedule ran out: stand in its last pose
                    self._steps_before = self.steps_taken()
                    self.schedule = []
                    if self.moving:
                        self._extend(now)
                        continue
                entry = self._standing()
            left = (count if math.isinf(entry.end)
                    else max(1, round((entry.end - now) / step)))
            chunk = min(every, count, left)
            rows = reference_table(entry.phase, now, chunk, step, joints)
            simulation.step(chunk, rows, 0)
            count -= chunk

    def _standing(self) -> _Scheduled:
        """The phase of standing still in :attr:`rest`'s pose: under the walk's
        force-controlled stance (:class:`.stance_control.StanceSettle`: the legs do not
        push against each other through the feet, however the feet were put down), or
        position control without one."""
        if self._entered is None or self._entered.phase.name != STAND:
            closed = np.ones(self.simulation.robot.joint_count, dtype=bool)
            stance = self.settings.stance_control
            pose = self.rest.pose
            references = (pose if stance is None
                          else StanceSettle(self.simulation, pose, stance))
            phase = Phase(STAND, math.inf, references, closed, feedback=stance is not None)
            self._measure_frame(None)
            self.simulation.joint_control["mode"] = phase.modes()
            self.simulation.stop_force_tracking()
            self._entered = _Scheduled(self.simulation.time, phase)
        return self._entered

    def _enter(self, entry: _Scheduled) -> _Scheduled | None:
        """Begin ``entry``: a walk whose command has changed since it was scheduled is
        dropped for the new command, a walk whose gate refuses the stance is dropped (the
        robot stands there); the joints closed-loop, force tracking stopped (a walk phase
        starts its own)."""
        simulation = self.simulation
        walk = entry.walk
        if walk is not None:
            reason = None
            if walk.command != self._command:
                reason = "command changed"
            elif entry.phase.gate is not None:
                reason, _ = entry.phase.gate(simulation)
                if reason is not None:
                    self.message = f"walk stopped: {reason}"
                    self.speed = self.yaw_rate = 0.0
            if reason is not None:  # stand in the walk's first pose, or walk on
                self.schedule = self.schedule[: self.schedule.index(entry)]
                self.rest = _Rest(walk.plan.references[0], walk.sway(walk.start),
                                  walk, 0.0)
                self._extend(simulation.time)
                entry = self._current(simulation.time)
                if entry is None:
                    return None
        self._measure_frame(entry.walk)
        simulation.joint_control["mode"] = entry.phase.modes()
        simulation.stop_force_tracking()
        self._entered = entry
        return entry

    def _measure_frame(self, walk: _Walk | None) -> None:
        """Beginning a phase after a turning walk: the walking frame is the yaw the
        turn left the body in."""
        if self._turned and (walk is None or not walk.turns):
            self.yaw = float(thorax_attitude(self.simulation)[2])
        self._turned = walk is not None and walk.turns
