"""Measure every closed-loop figure of thesis 4.3 and 5.5 for both controller sets: our
tuning (``thesis-rig`` / ``crr-quadruped``) and the thesis controller set
(``thesis-rig-thesis-pid`` / ``crr-quadruped-thesis-pid``), and the Table 3 cost profile.

:func:`measure_comparison` runs it all (about a minute on one core) and returns a
:class:`Comparison`; :mod:`pneumaquad.validation.comparison_page` writes the page.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pneumaquad.params import load_rig
from pneumaquad.reporting.component_costs import ComponentCost, component_costs
from pneumaquad.reporting.cost_table import CostTable, measure_cost_table
from pneumaquad.validation.calibration import THESIS_ALPHA_GAIN_SCALE
from pneumaquad.validation.leg_loop import (
    FootCycleFigures,
    JointFigures,
    foot_cycle_figures_of,
    foot_cycle_tracks,
    joint_figures,
)
from pneumaquad.validation.published import (
    BETA_RISE_TO_GAMMA,
    BETA_SINE_LAG,
    GAMMA_SINE_LAG,
    LEG_LAG_TOLERANCE,
    RIG_LAG_TOLERANCE,
    RIG_SINE_LAG_BOUNDS,
    RIG_TIME_CONSTANT,
    RIG_TIME_CONSTANT_TOLERANCE,
)
from pneumaquad.validation.rig_loop import RigLoopFigures, rig_loop_figures

__all__ = [
    "CONTROLLER_SETS",
    "WALK_DISTANCE",
    "Comparison",
    "ControllerSet",
    "SetFigures",
    "Target",
    "measure_comparison",
    "targets_of",
]


@dataclass(frozen=True)
class ControllerSet:
    """A named pair of parameter sets, the rig's and the robot's (``phrase``: the label
    as a sentence names it)."""

    label: str
    rig: str
    robot: str
    phrase: str


#: Our tuning (the defaults) and the thesis controller set.
CONTROLLER_SETS = (
    ControllerSet("our tuning", "thesis-rig", "crr-quadruped", "our tuning"),
    ControllerSet("thesis set", "thesis-rig-thesis-pid", "crr-quadruped-thesis-pid",
                  "the thesis set"),
)


@dataclass
class SetFigures:
    """Everything measured for one controller set.

    Attributes
    ----------
    rig : RigLoopFigures
        Rig step time constants and sine lags.
    joints : dict of str to JointFigures
        Fast-sine and step figures of alpha, beta and gamma.
    walking : dict of float to list of FootCycleFigures
        Walking-motion figures per alpha gain scale (1 and 0.75).
    walking_tracks : dict of float to tuple
        The walking motion's time [s] and per-joint (angle, reference) [rad] per scale.
    walk : dict
        The judgement of the quadruped's default walk of :data:`WALK_DISTANCE` on flat
        ground (``robot walk``; summary.json's ``"walking"``).
    """

    rig: RigLoopFigures
    joints: dict[str, JointFigures]
    walking: dict[float, list[FootCycleFigures]]
    walking_tracks: dict[float, tuple[np.ndarray, dict]] = field(repr=False)
    walk: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Target:
    """One closed-loop row of the comparison: a figure, its target and whether it is met.

    Attributes
    ----------
    claim : str
        What is compared.
    published : str
        The thesis's figure as printed.
    target : str
        The target in words.
    value : float
        Our figure.
    unit : str
        Its unit.
    met : bool
        Whether the target is met.
    shown : str
        How the value is written, where not as a number with its unit.
    """

    claim: str
    published: str
    target: str
    value: float
    unit: str
    met: bool
    shown: str = ""


@dataclass
class Comparison:
    """The measured figures of both controller sets and the cost profile."""

    sets: dict[str, SetFigures]
    cost_table: CostTable
    components: list[ComponentCost]
    wall_time: float


def _within(value: float, target: float, tolerance: float) -> bool:
    return abs(value / target - 1.0) <= tolerance


def targets_of(figures: SetFigures) -> list[Target]:
    """The closed-loop rows of issue table for one controller set, with their targets
    (:mod:`pneumaquad.validation.published`)."""
    rig, joints = figures.rig, figures.joints
    rows = [Target("rig step time constant", "sim 0.082 s, real 0.085 s",
                   f"0.082 s ± {RIG_TIME_CONSTANT_TOLERANCE:.0%}", rig.time_constant, "s",
                   _within(rig.time_constant, RIG_TIME_CONSTANT, RIG_TIME_CONSTANT_TOLERANCE))]
    for index, (rate, bound) in enumerate(zip(rig.sine_rates, RIG_SINE_LAG_BOUNDS,
                                              strict=True)):
        value = rig.sine_lags[index]
        if index == 0:
            text, met = f"{bound:g} s ± {RIG_LAG_TOLERANCE:.0%}", _within(value, bound,
                                                                          RIG_LAG_TOLERANCE)
        else:
            text, met = f">= {(1 - RIG_LAG_TOLERANCE) * bound:.3g} s", (
                value >= (1 - RIG_LAG_TOLERANCE) * bound)
        rows.append(Target(f"rig sine lag at {rate:g} rad/s", f"real >= {bound:g} s", text,
                           value, "s", met))
    gamma, beta = joints["gamma"], joints["beta"]
    rows.append(Target("gamma sine lag", "sim > 0.15 s, real about 0.2 s",
                       f"{GAMMA_SINE_LAG:g} s ± {LEG_LAG_TOLERANCE:.0%}", gamma.sine_lag, "s",
                       _within(gamma.sine_lag, GAMMA_SINE_LAG, LEG_LAG_TOLERANCE)))
    rows.append(Target("beta fast-sine lag", "sim 0.16 s, real 0.2 s",
                       f"{BETA_SINE_LAG:g} s ± {LEG_LAG_TOLERANCE:.0%}", beta.sine_lag, "s",
                       _within(beta.sine_lag, BETA_SINE_LAG, LEG_LAG_TOLERANCE)))
    ratio = beta.rise_time / gamma.rise_time
    rows.append(Target("beta step rise time / gamma's", "beta a slower version of gamma",
                       f"> 1 (calibrated to {BETA_RISE_TO_GAMMA:g})", ratio, "-", ratio > 1.0))
    full, reduced = (figures.walking[scale][0] for scale in (1.0, THESIS_ALPHA_GAIN_SCALE))
    rows.append(Target("walking motion: alpha RMSE, gain 1 -> 0.75", "10.2 deg -> 7.3 deg",
                       "lower at 0.75", reduced.rmse - full.rmse, "deg",
                       reduced.rmse < full.rmse,
                       f"{full.rmse:.2f} deg -> {reduced.rmse:.2f} deg"))
    return rows


#: Distance of the walk that decides which controller set is the default [m].
WALK_DISTANCE = 0.5


def _walk(robot_params: str) -> dict:
    """The default walk of :data:`WALK_DISTANCE` on flat ground with ``robot_params``."""
    from pneumaquad.locomotion.walk_run import run_walk
    from pneumaquad.locomotion.walking import WalkSettings
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.simulation import RobotSimulation

    simulation = RobotSimulation(build_robot(load_robot(robot_params), "quadruped", "flat", 0))
    with tempfile.TemporaryDirectory() as folder:
        walk = run_walk(simulation, WalkSettings(distance=WALK_DISTANCE), Path(folder) / "walk")
    return walk.outcome or {"success": False, "reasons": ["the walk did not begin"]}


def _measure_set(controller_set: ControllerSet) -> SetFigures:
    rig = rig_loop_figures([load_rig(controller_set.rig)])[0]
    joints = {joint: joint_figures(joint, controller_set.robot)
              for joint in ("gamma", "beta", "alpha")}
    walking, tracks = {}, {}
    for scale in (1.0, THESIS_ALPHA_GAIN_SCALE):
        tracks[scale] = foot_cycle_tracks(scale, controller_set.robot)
        walking[scale] = foot_cycle_figures_of(*tracks[scale], scale)
    return SetFigures(rig, joints, walking, tracks, _walk(controller_set.robot))


def measure_comparison(cost_repeats: int = 15,
                       progress: Callable[[int, int], None] | None = None) -> Comparison:
    """Measure both controller sets and the Table 3 profile.

    Parameters
    ----------
    cost_repeats : int
        Timed repeats of the cost table and of each component loop.
    progress : callable, optional
        Called with (parts done, parts) after each of the four parts.
    """
    started = time.perf_counter()
    sets = {}
    for done, controller_set in enumerate(CONTROLLER_SETS):
        sets[controller_set.label] = _measure_set(controller_set)
        if progress is not None:
            progress(done + 1, 4)
    cost = measure_cost_table("thesis-rig", duration=10.0, repeats=cost_repeats)
    if progress is not None:
        progress(3, 4)
    components = component_costs(load_rig("thesis-rig"), cost_repeats)
    if progress is not None:
        progress(4, 4)
    return Comparison(sets, cost, components, time.perf_counter() - started)
