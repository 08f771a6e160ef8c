"""A judged walk: the crawl gait played on the robot, written to a run folder and judged.

:func:`run_walk` is the one call behind ``pneumaquad robot walk`` and the demo's walk: it
checks the settings against :data:`WALK_SETTINGS` and plans the gait
(:func:`.walking.walking_phases`; settings out of range or that the gait cannot meet raise
:class:`WalkSettingsError` naming the fields), creates the run folder and plays the phases
(:func:`pneumaquad.robot.experiment.run_phases`), judges the walk
(:func:`.walking.walking_outcome`, with the tip-over margin and the plan's own margin and
reach), draws ``walking.png`` and adds the judgement to ``summary.json`` under
``"walking"`` through :class:`pneumaquad.io.run_folder.RunFolderWriter`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.run_folder import RunFolderWriter, create_run_folder, drawing_plots
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.robot.experiment import Phase, RobotRun, run_phases
from pneumaquad.robot.simulation import RobotSimulation

from .capacity import check_supply
from .reach import UnreachablePlanError
from .walk import WalkPlan
from .walk_settings import (
    GAIT_FIELDS,
    REACH_FIELDS,
    WALK_SETTINGS,
    WalkSettings,
    WalkSettingsError,
    check_walk_settings,
)
from .walking import (
    leg_posture,
    reachable_plan,
    tip_over_series,
    walking_outcome,
    walking_phases,
)
from .waypoints import waypoint_outcome, waypoint_phases

__all__ = ["GAIT_FIELDS", "REACH_FIELDS", "WALKING_FIGURE", "WALK_SETTINGS",
           "WAYPOINTS_FIGURE", "JudgedWalk", "WalkSettingsError", "check_walk_settings",
           "plan_walking", "run_walk", "run_waypoints"]

#: The walking figure of a judged walk's run folder.
WALKING_FIGURE = "walking.png"
#: The path figure of a waypoint walk's run folder.
WAYPOINTS_FIGURE = "waypoints.png"


@dataclass
class JudgedWalk:
    """Outcome of :func:`run_walk`.

    Attributes
    ----------
    run : RobotRun
        The run (recording, summary with ``"walking"``, folder).
    plan : WalkPlan
        The planned references.
    outcome : dict or None
        The judgement (:func:`.walking.walking_outcome` plus the planned smallest static
        margin and unreachable IK samples, and under ``"stance"`` the verdict of the
        stance the walk began from); a failure with the stance's reasons when the stance
        was not verified and the walk did not begin
        (:class:`~pneumaquad.robot.stance_check.StanceCheck`); None when the run was
        interrupted or diverged before the walk began.
    figure : Path or None
        ``walking.png`` of a judged walk (None inside
        :func:`~pneumaquad.io.run_folder.scratch_run_folders`).
    """

    run: RobotRun
    plan: WalkPlan
    outcome: dict[str, Any] | None
    figure: Path | None

    @property
    def folder(self) -> Path:
        """The run folder."""
        return self.run.folder


def plan_walking(simulation: RobotSimulation,
                 settings: WalkSettings) -> tuple[list[Phase], WalkPlan, WalkSettings]:
    """:func:`.walking.walking_phases` after :func:`check_walk_settings`, with the cycle
    shortened where the legs cannot reach the plan of the one asked
    (:func:`.walking.reachable_plan`, whose posture it walks about); returns the phases,
    the plan and the settings walked.

    Raises
    ------
    WalkSettingsError
        For a field out of range, settings the gait refuses (its message, with the
        values of :data:`GAIT_FIELDS`), or a plan the legs cannot reach (the leg, its
        phase and the joint limit; :data:`REACH_FIELDS`).
    """
    check_walk_settings(settings)
    try:
        settings, posture = reachable_plan(simulation.robot, settings)
        return (*walking_phases(simulation, settings, posture), settings)
    except UnreachablePlanError as error:
        raise WalkSettingsError(
            f"the legs cannot walk heading {math.degrees(settings.heading):g}° at "
            f"{settings.speed:g} m/s with a {settings.period:g} s cycle and a "
            f"{settings.step_height:g} m step: {error}", REACH_FIELDS) from None
    except ValueError as error:
        raise WalkSettingsError(
            f"the gait cannot be planned with duty factor {settings.duty_factor:g}, lift "
            f"fraction {settings.lift_fraction:g}, transfer gap {settings.transfer_gap:g} "
            f"and a static margin of {settings.minimum_margin:g} m: {error}",
            GAIT_FIELDS) from None


def run_walk(
    simulation: RobotSimulation,
    settings: WalkSettings,
    output: Path | None = None,
    description: str | None = None,
    progress: Callable[[float, float], None] | None = None,
    figure_title: str | None = None,
    clock: StageClock | None = None,
    on_sample: Callable[[float, np.ndarray], None] | None = None,
) -> JudgedWalk:
    """Stand up, walk, stop; write the run folder and judge the walk (module docstring).

    Parameters
    ----------
    simulation : RobotSimulation
        The free quadruped.
    settings : WalkSettings
    output : Path, optional
        Run folder; default ``runs/walk-<environment>-<time>``. Nothing is created when the
        settings are refused.
    description : str, optional
        For the summary; default ``"quadruped: walk <distance> m on <environment>"``.
    progress : callable, optional
        Called with (simulated time, total time) [s] as the run goes.
    figure_title : str, optional
        Title of ``walking.png``.
    clock : StageClock, optional
        Receives the wall time of the planning, of each stage of the run
        (:func:`~pneumaquad.robot.experiment.run_phases`) and of the judgement.
    on_sample : callable, optional
        Given to :func:`~pneumaquad.robot.experiment.run_phases`: called with (simulated
        time [s], qpos) of each recorded sample, e.g. to render the video while the run goes.

    Raises
    ------
    WalkSettingsError
        Before anything runs (:func:`plan_walking`).
    InsufficientSupplyError
        Before anything runs: the supply is below what statics asks to stand and walk
        (:func:`.capacity.check_supply`).
    SimulationDivergedError
        After writing the run folder, when the simulation diverged (not judged).
    """
    clock = StageClock() if clock is None else clock
    with clock.stage("walk plan"):
        phases, plan, settings = plan_walking(simulation, settings)
        check_supply(simulation, leg_posture(plan.references[0]), walking=True)
    robot = simulation.robot
    where = (f"{math.degrees(settings.turn):g}° in place on {robot.environment}"
             if settings.turning_in_place else f"{settings.distance:g} m on {robot.environment}")
    folder = create_run_folder(output, f"walk-{robot.environment}")
    verb = "turn" if settings.turning_in_place else "walk"
    run = run_phases(simulation, phases, folder, description or f"quadruped: {verb} {where}",
                     progress, clock=clock, on_sample=on_sample)
    stance = run.summary.get("checks", {}).get("walk")
    stopped = run.summary.get("stopped before")
    if stopped is not None and stopped["phase"] == "walk":
        outcome = {"success": False, "reasons": [stopped["reason"]], "stance": stance,
                   "period [s]": settings.period}
        return JudgedWalk(run, plan, _recorded(run, outcome), None)
    if run.interrupted or "walk" not in run.summary["phases"]:
        return JudgedWalk(run, plan, None, None)
    with clock.stage("walk judgement"):
        tip_over = tip_over_series(run.recording, run.summary, robot, plan)
        outcome = walking_outcome(run.recording, run.summary, settings, robot, tip_over)
        outcome["planned smallest static margin [m]"] = float(plan.margins.min())
        outcome["planned unreachable IK samples [count]"] = int(
            sum(plan.cycle.unreachable_counts.values()))
        outcome["stance"] = stance
        outcome["period [s]"] = settings.period
    figure = None
    if drawing_plots():
        with clock.stage("plots"):
            from pneumaquad.reporting.robot_plots import plot_walking  # Matplotlib: slow

            figure = plot_walking(run.recording, robot.legs, folder / WALKING_FIGURE,
                                  tip_over, figure_title or f"{verb} {where}")
    return JudgedWalk(run, plan, _recorded(run, outcome), figure)


def run_waypoints(
    simulation: RobotSimulation,
    settings: WalkSettings,
    waypoints: np.ndarray,
    output: Path | None = None,
    progress: Callable[[float, float], None] | None = None,
    clock: StageClock | None = None,
    on_sample: Callable[[float, np.ndarray], None] | None = None,
) -> JudgedWalk:
    """Stand up, walk to each of ``waypoints`` (n, 2) [m] in turn, stop
    (:mod:`.waypoints`); write the run folder, judge every walk and every waypoint
    (:func:`.waypoints.waypoint_outcome`), draw ``walking.png`` and ``waypoints.png`` and
    add the judgement to ``summary.json`` under ``"walking"``. Arguments as
    :func:`run_walk`'s; the result's ``plan`` is the first walk's.

    Raises
    ------
    WalkSettingsError
        Before anything runs: a setting out of range, or a leg of the path the gait or
        the legs cannot walk (:func:`.waypoints.waypoint_phases`).
    InsufficientSupplyError
        Before anything runs (:func:`.capacity.check_supply`).
    """
    clock = StageClock() if clock is None else clock
    check_walk_settings(settings)
    with clock.stage("walk plan"):
        phases, path = waypoint_phases(simulation, settings, waypoints)
        for leg in path:  # each walk of the path in its own posture
            check_supply(simulation, leg_posture(leg.plan.references[0]), walking=True)
    robot = simulation.robot
    folder = create_run_folder(output, f"waypoints-{robot.environment}")
    description = (f"quadruped: walk through {len(path)} waypoints on {robot.environment}")
    run = run_phases(simulation, phases, folder, description, progress, clock=clock,
                     on_sample=on_sample)
    if run.interrupted or path[0].phase not in run.summary["phases"]:
        stopped = run.summary.get("stopped before")
        outcome = None if stopped is None else {
            "success": False, "reasons": [f"{stopped['phase']}: {stopped['reason']}"],
            "legs": []}
        return JudgedWalk(run, path[0].plan,
                          None if outcome is None else _recorded(run, outcome), None)
    with clock.stage("walk judgement"):
        outcome = waypoint_outcome(run.recording, run.summary, simulation, path)
        stopped = run.summary.get("stopped before")
        if stopped is not None:
            outcome["success"] = False
            outcome["reasons"] = [*outcome["reasons"],
                                  f"{stopped['phase']}: {stopped['reason']}"]
        tip_over = np.full(run.recording["time [s]"].shape, np.nan)
        for leg in path:
            if leg.phase in run.summary["phases"]:
                series = tip_over_series(run.recording, run.summary, robot, leg.plan,
                                         leg.phase)
                tip_over = np.where(np.isfinite(series), series, tip_over)
    with clock.stage("plots"):
        from pneumaquad.reporting.robot_plots import plot_walking, plot_waypoints

        figure = plot_walking(run.recording, robot.legs, folder / WALKING_FIGURE, tip_over,
                              f"walk through {len(path)} waypoints")
        plot_waypoints(run.recording, np.array([leg.target for leg in path]),
                       np.array([judged["reached [m]"] for judged in outcome["legs"]]),
                       np.array(outcome["start [m]"] or [0.0, 0.0]), folder / WAYPOINTS_FIGURE)
    return JudgedWalk(run, path[0].plan, _recorded(run, outcome), figure)


def _recorded(run: RobotRun, outcome: dict[str, Any]) -> dict[str, Any]:
    """``outcome``, added to the run's summary (``"walking"``) and to its folder's."""
    RunFolderWriter(run.folder).update_summary({"walking": outcome})
    run.summary["walking"] = outcome
    return outcome
