"""Walking in the console: the command line's walk driven live, and shared control.

Modes:

``off``        the legs hold their references (the styluses drive the front feet);
``automatic``  the walk of ``pneumaquad robot walk``
               (:class:`pneumaquad.locomotion.live_walk.LiveWalk`: the same crawl,
               settings, feedback and verified start) at the commanded body speed and
               heading (GUI sliders or the keyboard of the terminal running the console,
               :mod:`.keyboard`); a new command takes effect at the end of the gait
               cycle in progress, the feet re-placed between two walks;
``shared``     the operator places the front feet with the styluses (gizmos or UDP
               devices): a front foot's foothold is its stylus target on the ground; the
               rear legs follow their front legs and the body follows the feet. The
               footholds are the operator's, chosen one step at a time, so this mode
               plans step by step (:class:`pneumaquad.gait.online.OnlineCrawl`, a
               discontinuous crawl with the same step height and planned margin,
               :class:`pneumaquad.gait.settings.CrawlSettings`).

In shared control, before each chunk :meth:`ConsoleWalking.before_chunk` advances the
crawl by the chunk's duration, refusing a lift that the *measured* state would not support
(:func:`pneumaquad.gait.crawl.refuse_lift` with the measured feet of the legs the crawl
has on the ground and the whole robot's measured centre of mass), commands all twelve
joints through the leg IK (clamped into the limits) and, like the command line's walk,
sets the stance legs' cylinders to carry their statics share of the weight
(:func:`pneumaquad.locomotion.stance_control.track_stance_loads` with the crawl's
:meth:`~pneumaquad.gait.online.OnlineCrawl.load_shares`). Its feet are planned in the
*walking frame*: world axes turned by the thorax's yaw when walking began, and given to
the legs in that frame, so a body that has turned is turned back by the legs.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from pneumaquad.gait.crawl import LEGS, refuse_lift
from pneumaquad.gait.online import OnlineCrawl, OnlineCrawlSettings
from pneumaquad.gait.stability import centre_of_mass
from pneumaquad.locomotion.live_walk import LiveWalk
from pneumaquad.locomotion.stance_control import StanceControlSettings, track_stance_loads
from pneumaquad.locomotion.walk import standing_feet, thorax_rotation
from pneumaquad.locomotion.walk_settings import WalkSettings
from pneumaquad.locomotion.walking import WALKING_ANGLES
from pneumaquad.robot.kinematics import DHTable, foot_jacobian, forward_kinematics_dh
from pneumaquad.robot.leg_ik import exact_solutions
from pneumaquad.robot.legs import leg_dh_table
from pneumaquad.robot.recording import thorax_attitude
from pneumaquad.robot.simulation import RobotSimulation

__all__ = ["WALKING_MODES", "ConsoleWalking", "reach"]

WALKING_MODES = ("off", "automatic", "shared")
#: Fastest commanded body speed [m/s].
MAX_SPEED = 0.05
#: Fastest commanded yaw rate [rad/s] of the automatic walk (5°/s).
MAX_YAW_RATE = math.radians(5.0)
#: The force-controlled stance of the console's crawl (that of ``pneumaquad robot walk``).
DEFAULT_STANCE = StanceControlSettings()


def reach(table: DHTable, target: np.ndarray, current: np.ndarray,
          iterations: int = 4, damping: float = 0.02) -> np.ndarray:
    """Joint angles [rad] for a foot ``target`` [m] (thorax frame), inside the limits.

    The analytic IK when the target is reachable; otherwise a few damped least-squares
    steps from ``current`` clipped into the limits (λ = ``damping`` [m]) — the clamped
    exact search of :func:`pneumaquad.robot.leg_ik.inverse_kinematics` is too slow
    for every chunk of a live gait, and a swing briefly out of reach only needs the
    nearest feasible pose approximately.
    """
    solutions = exact_solutions(table, target)
    if solutions:
        nearest = min(solutions, key=lambda angles: float(np.linalg.norm(angles - current)))
        return np.clip(nearest, table.lower_limits, table.upper_limits)
    angles = np.clip(current, table.lower_limits, table.upper_limits)
    for _ in range(iterations):
        jacobian = foot_jacobian(table, angles)
        error = target - forward_kinematics_dh(table, angles)
        step = jacobian.T @ np.linalg.solve(jacobian @ jacobian.T + damping**2 * np.eye(3),
                                            error)
        angles = np.clip(angles + step, table.lower_limits, table.upper_limits)
    return angles


class ConsoleWalking:
    """The console's walking controller for one live :class:`RobotSimulation`.

    Parameters
    ----------
    simulation : RobotSimulation
        A free quadruped (other configurations cannot walk: the mode stays ``off``).
    settings : OnlineCrawlSettings, optional
        The shared-control crawl's.
    stance : StanceControlSettings or None, optional
        Force-controlled stance while walking (the CLI walk's default); None: plain
        position control of every leg.
    walk : WalkSettings, optional
        The automatic walk's (the defaults of ``robot walk``; its stance is ``stance``).
    """

    def __init__(self, simulation: RobotSimulation,
                 settings: OnlineCrawlSettings | None = None,
                 stance: StanceControlSettings | None = DEFAULT_STANCE,
                 walk: WalkSettings | None = None) -> None:
        self.simulation = simulation
        self.settings = settings or OnlineCrawlSettings()
        self.stance = stance
        self.walk_settings = replace(walk or WalkSettings(), stance_control=stance)
        #: The automatic walk (automatic mode only).
        self.live: LiveWalk | None = None
        robot = simulation.robot
        self.available = robot.free and tuple(robot.legs) == LEGS
        self.mode = "off"
        self.speed = 0.0
        self.heading = 0.0
        self.yaw_rate = 0.0
        self.crawl: OnlineCrawl | None = None
        #: World → walking frame (2×2): the world axes turned by the yaw held while walking.
        self.to_frame = np.eye(2)
        self.message = ""
        if self.available:
            self.tables = [leg_dh_table(robot, leg) for leg in robot.legs]
            self.to_thorax = thorax_rotation(robot).T  # body → thorax frame

    def set_mode(self, mode: str) -> None:
        """Switch mode; walking starts from where the feet stand (automatic: the present
        pose is the standing pose it walks from and returns to)."""
        if mode not in WALKING_MODES:
            raise ValueError(f"walking mode {mode!r}: expected one of {WALKING_MODES}")
        if mode != "off" and not self.available:
            self.message = "walking needs the free quadruped configuration"
            mode = "off"
        if mode != self.mode:
            self.crawl = self.live = None
            self.simulation.stop_force_tracking()
        self.mode = mode
        if mode == "automatic" and self.live is None:
            self.live = LiveWalk(self.simulation, self.walk_settings)
        if mode == "shared" and self.crawl is None:
            simulation = self.simulation
            robot = simulation.robot
            neutral = standing_feet(robot, WALKING_ANGLES)
            yaw = self._yaw()
            cos, sin = math.cos(yaw), math.sin(yaw)
            self.to_frame = np.array([[cos, sin], [-sin, cos]])
            thorax = self._in_frame(simulation.data.xpos[robot.thorax_id])
            com = self._in_frame(centre_of_mass(simulation.model, simulation.data)) - thorax
            feet = self._in_frame(simulation.foot_positions())
            self.crawl = OnlineCrawl(neutral, com, thorax, self.settings, footholds=feet)
            self.crawl.shared = True
        if mode != "off":
            self.command(self.speed, self.heading)

    def command(self, speed: float, heading: float, yaw_rate: float | None = None) -> None:
        """Body speed [m/s] (clipped to ±:data:`MAX_SPEED`), heading [rad] and, in
        automatic mode, yaw rate [rad/s] (clipped to ±:data:`MAX_YAW_RATE`; the shared
        crawl does not turn); ``yaw_rate`` None keeps the present one."""
        self.speed = float(np.clip(speed, -MAX_SPEED, MAX_SPEED))
        self.heading = float(heading)
        if yaw_rate is not None:
            self.yaw_rate = float(np.clip(yaw_rate, -MAX_YAW_RATE, MAX_YAW_RATE))
        if self.live is not None:
            self.live.command(self.speed, self.heading, self.yaw_rate)

    def _in_frame(self, points: np.ndarray) -> np.ndarray:
        """xy [m] in the walking frame of world points (..., ≥2) [m]."""
        return np.asarray(points)[..., :2] @ self.to_frame.T

    def footholds_from_targets(self, targets: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Walking-frame xy [m] of foot targets given in the thorax frame [m], taken
        relative to the crawl's planned body (not the measured thorax, whose sway and sag would move
        the operator's footholds with it)."""
        if self.crawl is None:
            return {}
        from_thorax = self.to_thorax.T  # thorax → body frame
        return {leg: self.crawl.body + (from_thorax @ target)[:2]
                for leg, target in targets.items()}

    def place_front_feet(self, targets: dict[str, np.ndarray]) -> None:
        """Shared mode: the operator's front-foot targets (thorax frame [m], e.g. the
        styluses) become the front legs' footholds."""
        if self.crawl is not None:
            for leg, point in self.footholds_from_targets(targets).items():
                self.crawl.place(leg, point)

    def _yaw(self) -> float:
        return float(thorax_attitude(self.simulation)[2])

    @property
    def steps_taken(self) -> int:
        """Feet lifted since the walking mode began."""
        if self.live is not None:
            return self.live.steps_taken()
        return 0 if self.crawl is None else self.crawl.steps_taken

    def step(self, count: int) -> None:
        """Advance the simulation ``count`` control steps, walking as the mode asks."""
        if self.live is not None:
            self.live.step(count)
            return
        self.before_chunk(count * self.simulation.control_step)
        self.simulation.step(count)

    def before_chunk(self, interval: float) -> None:
        """Shared control: advance the crawl by ``interval`` [s] and command the joints
        for the chunk."""
        crawl = self.crawl
        if crawl is None:
            return
        simulation = self.simulation
        allowed = True
        if crawl.phase == "shift" and crawl.clock + interval >= crawl.settings.shift_time:
            feet = self._in_frame(simulation.foot_positions())
            com = self._in_frame(centre_of_mass(simulation.model, simulation.data))
            allowed = not refuse_lift(feet, crawl.stance(), LEGS.index(crawl.leg), com)
        crawl.advance(interval, allowed)
        # The walking frame is the body frame the crawl commands (the heading held).
        feet_body = crawl.feet_relative()
        angles = simulation.reference_angles.copy()
        for k, table in enumerate(self.tables):
            target = self.to_thorax @ feet_body[k]
            current = angles[3 * k : 3 * k + 3]
            angles[3 * k : 3 * k + 3] = reach(table, target, current)
        simulation.command_angles(angles)
        if self.stance is not None:
            track_stance_loads(simulation, crawl.load_shares(), self.stance.force_gain,
                               self.stance.stiffness)

    def status(self) -> str:
        """Markdown lines: mode, command, what the walk is doing, planned margin, steps,
        ⚠ a refused lift or a walk that could not go on."""
        if self.message and self.mode == "off":
            return self.message
        if self.crawl is None and self.live is None:
            return f"mode **{self.mode}**"
        lines = [f"mode **{self.mode}**, speed {1000 * self.speed:.0f} mm/s, heading "
                 f"{math.degrees(self.heading):.0f}°"
                 + (f", yaw rate {math.degrees(self.yaw_rate):+.1f}°/s"
                    if self.live is not None else "")]
        if self.live is not None:
            live = self.live
            doing = live.phase_name or "standing"
            margin = live.planned_margin()
            lines.append(f"{doing}" + ("" if math.isnan(margin) else
                                       f", planned margin {1000 * margin:.0f} mm")
                         + f", steps {live.steps_taken()}")
            if live.message:
                lines.append(f"⚠ {live.message}")
            return "  \n".join(lines)
        crawl = self.crawl
        lines.append(f"{crawl.phase} ({crawl.leg}), planned margin "
                     f"{1000 * crawl.margin():.0f} mm, steps {crawl.steps_taken}")
        if crawl.refusal:
            lines.append(f"⚠ {crawl.refusal}")
        return "  \n".join(lines)
