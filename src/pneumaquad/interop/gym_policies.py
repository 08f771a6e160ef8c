"""Baseline policies for the Gymnasium environment (:mod:`.gym_env`).

* :class:`CrawlGaitPolicy` — the project's crawl gait (:mod:`pneumaquad.gait`, planned
  on the robot by :func:`pneumaquad.locomotion.walk.robot_gait` and
  :func:`~pneumaquad.locomotion.walk.plan_walk` with the settings of
  :class:`pneumaquad.locomotion.walking.WalkSettings`) played open loop as joint-angle
  references, one per environment step, for ``action="angles"``. It is the gait of
  ``pneumaquad robot walk`` without that command's force-controlled stance, swing and
  heading corrections, which act on the cylinders directly and have no place in the
  action space: plain position control of the planned angles.
* :class:`RandomPolicy` — uniform samples of the action space, seeded.

A policy is called with the observation and returns the action; call :meth:`reset`
when the environment is reset.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from gymnasium import spaces

from pneumaquad.locomotion.walk import WalkPlan, plan_walk, robot_gait
from pneumaquad.locomotion.walking import WALKING_ANGLES, WalkSettings
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot

from .gym_terms import observation_slices

__all__ = ["CrawlGaitPolicy", "RandomPolicy"]

_ANGLES = observation_slices()["joint angles"]


class CrawlGaitPolicy:
    """The crawl gait as joint-angle references, one per environment step.

    Parameters
    ----------
    control_period : float [s]
        The environment's control period; the gait period must be a whole number of it.
    settings : WalkSettings
        Speed [m/s], duty factor, period [s], step height [m], planned static margin [m]
        …; default the settings ``pneumaquad robot walk`` uses (2 cm/s, 8 s cycles).
        The corrections (stance control, swing height, heading hold) are not used.
    parameters : str
        Robot parameter set the gait is planned on (the environment's).
    overrides : sequence of str
        Its parameter overrides.
    lead_in : float [s]
        Time to move linearly from the joint angles of the first observation to the
        gait's first pose (:attr:`initial_angles`) before the gait starts; 0 starts the
        gait at once (start the environment in :attr:`initial_angles` then).

    Notes
    -----
    After the lead-in the gait's first cycle (its start-up from a symmetric stance)
    plays once, then its steady cycle repeats for as long as the policy is called.
    """

    def __init__(self, control_period: float = 0.02, settings: WalkSettings | None = None,
                 parameters: str = "crr-quadruped", overrides: Sequence[str] = (),
                 lead_in: float = 1.0) -> None:
        settings = WalkSettings() if settings is None else settings
        steps_per_cycle = round(settings.period / control_period)
        if steps_per_cycle < 1 or abs(steps_per_cycle * control_period - settings.period) > 1e-9:
            raise ValueError(f"the gait period {settings.period} s should be a whole number "
                             f"of control periods ({control_period} s)")
        robot = build_robot(load_robot(parameters, list(overrides)), "quadruped", "flat")
        gait = robot_gait(
            robot, speed=settings.speed, heading=settings.heading,
            duty_factor=settings.duty_factor, period=settings.period,
            step_height=settings.step_height, angles=WALKING_ANGLES,
            minimum_margin=settings.minimum_margin, lift_fraction=settings.lift_fraction,
            transfer_gap=settings.transfer_gap, start_up=True,
        )
        #: Start-up cycle then one steady cycle, one row per environment step [rad].
        self.plan: WalkPlan = plan_walk(robot, gait, 2 * settings.period,
                                        control_step=control_period)
        self.settings = settings
        self.steps_per_cycle = steps_per_cycle
        self.lead_in_steps = round(lead_in / control_period)
        self._step = 0
        self._lead_from: np.ndarray | None = None

    @property
    def initial_angles(self) -> np.ndarray:
        """The gait's first pose (12,) [rad]: the robot's symmetric stance."""
        return self.plan.references[0].copy()

    def reset(self) -> None:
        """Start again from the lead-in (call after each environment reset)."""
        self._step = 0
        self._lead_from = None

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        """The joint-angle references (12,) [rad] for this step."""
        step = self._step
        self._step += 1
        if step < self.lead_in_steps:
            if self._lead_from is None:
                self._lead_from = np.asarray(observation, dtype=float)[_ANGLES].copy()
            fraction = (step + 1) / self.lead_in_steps
            return self._lead_from + fraction * (self.plan.references[0] - self._lead_from)
        index = step - self.lead_in_steps
        cycle = self.steps_per_cycle
        if index >= 2 * cycle:  # the steady cycle repeats
            index = cycle + (index - cycle) % cycle
        return self.plan.references[index].copy()


class RandomPolicy:
    """Uniform random actions from ``action_space``, drawn from its own generator."""

    def __init__(self, action_space: spaces.Box, seed: int | None = None) -> None:
        self.space = spaces.Box(action_space.low, action_space.high,
                                dtype=action_space.dtype, seed=seed)

    def reset(self) -> None:
        """Nothing to reset (the generator goes on)."""

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        """A uniform sample of the action space."""
        return self.space.sample()
