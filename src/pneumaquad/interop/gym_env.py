"""The quadruped on its 12 pneumatic joints as a Gymnasium environment.

:class:`QuadrupedEnv` wraps :class:`pneumaquad.robot.simulation.RobotSimulation` of the
``crr-quadruped`` parameter set in the ``quadruped`` configuration (free thorax): every
cylinder, valve, chamber and seal of the coupled simulation runs as in the rest of the
package. It is registered as ``pneumaquad/Quadruped-v0`` when :mod:`pneumaquad.interop`
is imported (docs/gymnasium.md):

>>> import gymnasium, pneumaquad.interop
>>> env = gymnasium.make("pneumaquad/Quadruped-v0", action="angles")  # doctest: +SKIP

Actions (held for one control period, default 20 ms = 20 simulation steps of 1 ms):

``action="angles"``   12 joint-angle references [rad] for the joints' closed-loop
                      position controllers, Box within each joint's limits;
``action="voltage"``  12 valve voltages [V] applied open loop, Box within each valve's
                      [min_voltage, max_voltage] (0–10 V, 5.25 V closed centre).

Actions outside the Box are clipped into it (``info["action clipped"]`` says so);
a non-finite action is refused with ``ValueError``. Observations, reward and the fall
test: :mod:`.gym_terms`. An episode ends (``terminated``) on a fall or if the
simulation diverges; ``gymnasium.make`` adds the time limit (``truncated``) of the
registration, 1000 steps (20 s at the default period).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from pneumaquad.locomotion.walking import WALKING_ANGLES
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.simulation import RobotSimulation, SimulationDivergedError

from .gym_terms import (
    RewardWeights,
    body_rotation,
    has_fallen,
    normal_litres,
    observation_size,
    observation_slices,
    write_observation,
)

__all__ = ["ACTIONS", "QuadrupedEnv"]

ACTIONS = ("angles", "voltage")
_SLICES = observation_slices()
_ATTITUDE = _SLICES["thorax roll pitch yaw"].start
_HEIGHT = _SLICES["thorax height"].start


class QuadrupedEnv(gymnasium.Env[np.ndarray, np.ndarray]):
    """The quadruped walking on its 12 pneumatic joints (module docstring).

    Parameters
    ----------
    action : {"angles", "voltage"}
        Joint-angle references [rad] (closed loop) or valve voltages [V] (open loop).
    control_period : float [s]
        Time an action is held: a whole number of the simulation's control steps (1 ms
        in ``crr-quadruped``). Default 0.02.
    parameters : str
        Robot parameter set (shipped name or TOML path), default ``"crr-quadruped"``.
    overrides : sequence of str
        ``"section.key=value"`` parameter overrides, as ``--set`` on the command line.
    environment : str
        ``"flat"`` (default), ``"block"``, ``"ramp"`` or ``"rough"``.
    initial_angles : array-like, optional
        Pose [rad] the robot starts standing in: (alpha, beta, gamma) for every leg or 12
        angles; default the walking pose (0°, −20°, 80°) of :mod:`pneumaquad.locomotion`.
    reset_noise : float [rad]
        Each joint starts at its initial angle plus a uniform draw in ±``reset_noise``
        (from the environment's seeded generator); the controllers then hold the initial
        pose for ``settle_time``. Default 0.02 (≈ 1.1°); 0 starts every episode alike.
    settle_time : float [s]
        Closed-loop settling on the ground before the first observation. Default 0.5.
    lateral_weight, air_weight, fall_penalty : float
        Reward weights c_y [1/s], c_air [m/NL], P_fall [-] (:class:`.RewardWeights`).
    fall_height : float [m]
        Thorax height below which the robot has fallen. Default 0.15.
    fall_tilt : float [rad]
        |roll| or |pitch| above which the robot has fallen. Default 30°.
    render_mode : {None, "rgb_array"}
        ``"rgb_array"``: :meth:`render` returns a 480×640 RGB frame from a camera that
        tracks the thorax (needs an offscreen OpenGL backend, EGL or OSMesa).
    """

    # Gymnasium's class attribute; each instance replaces it with its own render_fps.
    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 50}  # noqa: RUF012

    def __init__(
        self,
        action: str = "angles",
        control_period: float = 0.02,
        parameters: str = "crr-quadruped",
        overrides: Sequence[str] = (),
        environment: str = "flat",
        initial_angles: Sequence[float] | np.ndarray | None = None,
        reset_noise: float = 0.02,
        settle_time: float = 0.5,
        lateral_weight: float = RewardWeights.lateral,
        air_weight: float = RewardWeights.air,
        fall_penalty: float = RewardWeights.fall,
        fall_height: float = 0.15,
        fall_tilt: float = math.radians(30.0),
        render_mode: str | None = None,
    ) -> None:
        if action not in ACTIONS:
            raise ValueError(f"action {action!r} should be one of {ACTIONS}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} should be None or 'rgb_array'")
        for name, value in (("reset_noise", reset_noise), ("settle_time", settle_time),
                            ("fall_tilt", fall_tilt)):
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        robot = build_robot(load_robot(parameters, list(overrides)), "quadruped", environment)
        self.sim = RobotSimulation(robot)
        dt = self.sim.control_step
        steps = round(control_period / dt)
        if steps < 1 or abs(steps * dt - control_period) > 1e-9 * max(1.0, control_period):
            raise ValueError(f"control_period {control_period!r} s should be a whole number "
                             f"(>= 1) of the simulation's control step, {dt:g} s")
        self.action_kind = action
        self.control_period = steps * dt
        self.steps_per_action = steps
        self.settle_steps = round(settle_time / dt)
        self.reset_noise = float(reset_noise)
        self.weights = RewardWeights(lateral_weight, air_weight, fall_penalty)
        self.fall_height, self.fall_tilt = float(fall_height), float(fall_tilt)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.control_period}
        count = robot.joint_count
        initial = np.asarray(WALKING_ANGLES if initial_angles is None else initial_angles,
                             dtype=float).ravel()
        if initial.size == 3:
            initial = np.tile(initial, len(robot.legs))
        if initial.shape != (count,) or not np.all(np.isfinite(initial)):
            raise ValueError(f"initial_angles should hold 3 or {count} finite angles [rad]")
        self.initial_angles = np.clip(initial, robot.lower_limits(), robot.upper_limits())
        if action == "angles":
            low, high = robot.lower_limits(), robot.upper_limits()
        else:
            valves = [robot.actuators[t].valve for t in robot.joint_types]
            low = np.array([v.min_voltage for v in valves])
            high = np.array([v.max_voltage for v in valves])
        self.action_space = spaces.Box(low, high, dtype=np.float64)
        size = observation_size()
        low_obs, high_obs = np.full(size, -np.inf), np.full(size, np.inf)
        for block in ("cap pressures", "rod pressures", "foot normal forces"):
            low_obs[_SLICES[block]] = 0.0
        self.observation_space = spaces.Box(low_obs, high_obs, dtype=np.float64)
        self._to_body = body_rotation(self.sim)
        self._observation = np.zeros(size)
        self._start = np.zeros(2)  # thorax x, y [m] at the end of reset
        self._previous_x = 0.0
        self._previous_air = 0.0
        self._start_air = 0.0  # [kg] drawn at the end of reset
        self._to_normal_litres = normal_litres(self.sim, 1.0)
        self._diverged = False
        self._reset_done = False

    # --- gymnasium API -----------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Stand the robot on the ground in the initial pose (plus seeded noise) and let
        the joint controllers hold it for ``settle_time``; returns (observation, info)."""
        super().reset(seed=seed)
        sim = self.sim
        count = sim.robot.joint_count
        noise = self.np_random.uniform(-self.reset_noise, self.reset_noise, count)
        angles = self.initial_angles + noise
        sim.set_pose(angles)  # thorax at the model's start pose, to find the lowest foot
        thorax = sim.data.qpos[0:3].copy()
        thorax[2] -= sim.foot_positions()[:, 2].min()  # lowest foot on the ground (z = 0)
        sim.set_pose(angles, thorax_position=thorax, thorax_quaternion=sim.data.qpos[3:7].copy())
        sim.command_angles(self.initial_angles)
        self._diverged = False
        self._reset_done = True
        if self.settle_steps:
            sim.step(self.settle_steps)
        thorax_position = sim.data.xpos[sim.robot.thorax_id]
        self._start[:] = thorax_position[:2]
        self._previous_x = float(thorax_position[0])
        self._previous_air = self._start_air = sim.air_consumed()
        write_observation(sim, self._to_body, self._observation)
        return self._observation.copy(), self._info(0.0, False)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Hold ``action`` for one control period; returns (observation, reward,
        terminated, truncated, info) with the reward of :mod:`.gym_terms`."""
        if self._diverged or not self._reset_done:
            raise RuntimeError("call reset() first" if not self._reset_done else
                               "the simulation diverged in this episode: call reset()")
        command = np.asarray(action, dtype=np.float64).reshape(self.action_space.shape)
        if not np.all(np.isfinite(command)):
            raise ValueError(f"the action must be finite, got {action!r}")
        clipped = np.clip(command, self.action_space.low, self.action_space.high)
        sim = self.sim
        if self.action_kind == "angles":
            sim.command_angles(clipped)
        else:
            sim.command_voltages(clipped)
        try:
            sim.step(self.steps_per_action)
        except SimulationDivergedError:
            self._diverged = True
        if self._diverged:  # the last finite observation; the episode ends here
            info = self._info(0.0, True)
            info["action clipped"] = bool(np.any(clipped != command))
            return (self._observation.copy(), -self.weights.fall, True, False, info)
        observation = self._observation
        write_observation(sim, self._to_body, observation)
        thorax = sim.data.xpos[sim.robot.thorax_id]
        x, y = float(thorax[0]), float(thorax[1])
        air = sim.air_consumed()
        period = self.control_period
        weights = self.weights
        progress = x - self._previous_x
        air_litres = (air - self._previous_air) * self._to_normal_litres
        fell = has_fallen(observation[_HEIGHT], observation[_ATTITUDE],
                          observation[_ATTITUDE + 1], self.fall_height, self.fall_tilt)
        reward = (progress / period - weights.lateral * abs(y - self._start[1])
                  - weights.air * air_litres / period - (weights.fall if fell else 0.0))
        self._previous_x, self._previous_air = x, air
        info = self._info(progress, fell)
        info["action clipped"] = bool(np.any(clipped != command))
        return observation.copy(), float(reward), fell, False, info

    def render(self) -> np.ndarray | None:  # type: ignore[override]
        """An RGB frame (480, 640, 3) ``uint8`` of the present state (``render_mode``
        ``"rgb_array"``), else None. Each call opens and closes a renderer (tens of ms)."""
        if self.render_mode != "rgb_array":
            return None
        from pneumaquad.robot.video import render_frames

        qpos = self.sim.data.qpos.copy()[None, :]
        frames = render_frames(self.sim.model, np.array([self.sim.time]), qpos)
        try:
            return next(frames)
        finally:
            frames.close()

    # --- helpers -----------------------------------------------------------------------
    def _info(self, progress: float, fell: bool) -> dict[str, Any]:
        sim = self.sim
        thorax = sim.data.xpos[sim.robot.thorax_id]
        return {
            "time [s]": sim.time,
            "forward progress [m]": progress,
            "distance [m]": float(thorax[0] - self._start[0]),
            "lateral offset [m]": float(thorax[1] - self._start[1]),
            "air consumed [NL]": (sim.air_consumed() - self._start_air) * self._to_normal_litres,
            "fell": fell,
            "diverged": self._diverged,
        }
