"""Running a batch of cases, in whatever process: every case ends as a row, ok or failed.

A rig batch runs its cases together through the vectorised N-rig kernel
(:func:`pneumaquad.rig.simulate.simulate_rigs`: each rig's recording is the one it has run
alone); when one of them diverges, the batch runs again case by case so the others finish
and the diverging one is recorded with its error. A robot case builds its model, plays the
stand-up or the walk, and reads its figures from the run's summary. Any exception of a
case (parameters refused, divergence, a walk that cannot be planned) is its error; the
batch goes on. Nothing here depends on the executor, so a case's row is the same whichever
process runs it.
"""

from __future__ import annotations

import contextlib
import math
import shutil
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.run_folder import scratch_run_folders
from pneumaquad.params.errors import ParameterError, Problem
from pneumaquad.params.loader import load_rig, load_robot
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig import signals
from pneumaquad.rig.metrics import general_metrics, step_metrics, tracking_metrics
from pneumaquad.rig.simulate import RigResult, simulate_rig, simulate_rigs

from .run_options import RunSpec, parse_run_options
from .sampling import Case

__all__ = ["CaseInterruptedError", "CaseOutcome", "flat_figures", "run_batch", "walk_settings",
           "warm_up"]


class CaseInterruptedError(RuntimeError):
    """A case stopped by Ctrl-C: the study stops, the case is not recorded."""


@dataclass
class CaseOutcome:
    """One finished case: ``status`` "ok" or "failed", its error text, its figures, its
    wall time [s] (a batch's shared simulation time divided among its cases), where its
    run folder was kept, and a note on how the run went (a walk's or a stance check's
    reasons)."""

    index: int
    status: str
    error: str = ""
    metrics: dict[str, float] = field(default_factory=dict)
    wall_time: float = math.nan
    run_folder: str = ""
    note: str = ""


def _reasons(summary: Mapping[str, Any], run_kind: str) -> str:
    """The walk's reasons (success or failure), or the stance check's problems."""
    if run_kind == "robot-walk":
        walking = summary.get("walking")
        if not isinstance(walking, Mapping):
            return "not judged: the run stopped before the walk began"
        return "; ".join(str(reason) for reason in walking.get("reasons", []))
    check = summary.get("checks", {}).get("stance check", {})
    return "; ".join(str(reason) for reason in check.get("reasons", []))


def flat_figures(summary: Mapping[str, Any], prefix: str = "") -> dict[str, float]:
    """The numeric figures of a summary, nested tables joined with dots
    (``"walking.success"``); booleans as 1.0 / 0.0, missing values (None) as NaN."""
    figures: dict[str, float] = {}
    for key, value in summary.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            figures.update(flat_figures(value, f"{name}."))
        elif isinstance(value, (bool, int, float, np.number)):
            figures[name] = float(value)
        elif value is None:
            figures[name] = math.nan
    return figures


def _chosen(figures: Mapping[str, float], metrics: Sequence[str]) -> dict[str, float]:
    return {name: float(figures.get(name, math.nan)) for name in metrics}


def _error_text(error: BaseException) -> str:
    return f"{type(error).__name__}: {error}"


@dataclass
class _RigCase:
    case: Case
    setup: RigSetup
    signal: np.ndarray
    step_time: float | None
    prepared_in: float


def _prepare_rig(run: RunSpec, case: Case) -> _RigCase:
    started = time.perf_counter()
    setup = load_rig(run.params, [*run.overrides, *case.overrides])
    options = parse_run_options(run.kind, case.run_options, case.seed)
    dt = setup.simulation.control_step
    step_time = None
    if run.kind == "rig-step":
        valve = setup.actuator.valve
        if not valve.min_voltage <= options["voltage"] <= valve.max_voltage:
            raise ValueError(f"run.voltage {options['voltage']:g} V lies outside the valve's "
                             f"[{valve.min_voltage:g}, {valve.max_voltage:g}] V")
        step_time = options["step_time"]
        signal = signals.thesis_step_command(options["voltage"], valve.offset_voltage,
                                             valve.min_voltage, valve.max_voltage, dt,
                                             step_time, options["duration"])
    else:
        signal = signals.sine(options["mean"], options["amplitude"], options["frequency"],
                              options["duration"], dt)
    return _RigCase(case, setup, signal, step_time, time.perf_counter() - started)


def _rig_figures(run: RunSpec, metrics: tuple[str, ...], item: _RigCase,
                 result: RigResult) -> dict[str, float]:
    if result.interrupted:
        raise CaseInterruptedError(f"case {item.case.index} was interrupted")
    recording = result.recording
    figures = general_metrics(recording)
    if run.kind == "rig-step":
        figures.update(step_metrics(recording, item.step_time))
    else:
        figures.update(tracking_metrics(recording, item.setup.actuator.cylinder.stroke))
    return _chosen(figures, metrics)


def _run_rigs_together(run: RunSpec, metrics: tuple[str, ...],
                       items: list[_RigCase]) -> list[CaseOutcome]:
    """Rigs sharing step and length in one compiled call; on a divergence, one by one."""
    closed_loop = run.kind == "rig-sine"
    started = time.perf_counter()
    try:
        results = simulate_rigs([i.setup for i in items], np.array([i.signal for i in items]),
                                closed_loop)
    except Exception:  # a rig diverged (or another failed): each alone names its own
        return [_run_rig_alone(run, metrics, item) for item in items]
    share = (time.perf_counter() - started) / len(items)
    return [_rig_outcome(run, metrics, item, result, item.prepared_in + share)
            for item, result in zip(items, results, strict=True)]


def _rig_outcome(run: RunSpec, metrics: tuple[str, ...], item: _RigCase, result: RigResult,
                 spent: float) -> CaseOutcome:
    """A finished rig's row; figures that cannot be computed make it a failed case."""
    begun = time.perf_counter()
    try:
        figures = _rig_figures(run, metrics, item, result)
    except CaseInterruptedError:
        raise
    except Exception as error:  # the case's own problem: recorded, the batch goes on
        return CaseOutcome(item.case.index, "failed", _error_text(error),
                           _chosen({}, metrics), spent + time.perf_counter() - begun)
    return CaseOutcome(item.case.index, "ok", "", figures,
                       spent + time.perf_counter() - begun)


def _run_rig_alone(run: RunSpec, metrics: tuple[str, ...], item: _RigCase) -> CaseOutcome:
    started = time.perf_counter()
    try:
        result = simulate_rig(item.setup, item.signal, run.kind == "rig-sine")
    except Exception as error:  # diverged, or the reference solver gave up: recorded
        return CaseOutcome(item.case.index, "failed", _error_text(error),
                           _chosen({}, metrics),
                           item.prepared_in + time.perf_counter() - started)
    return _rig_outcome(run, metrics, item, result,
                        item.prepared_in + time.perf_counter() - started)


def _rig_batch(run: RunSpec, metrics: tuple[str, ...], cases: Sequence[Case]
               ) -> list[CaseOutcome]:
    outcomes: dict[int, CaseOutcome] = {}
    groups: dict[tuple[Any, ...], list[_RigCase]] = {}
    for case in cases:
        started = time.perf_counter()
        try:
            item = _prepare_rig(run, case)
        except Exception as error:  # a case's own problem: recorded, the batch goes on
            outcomes[case.index] = CaseOutcome(case.index, "failed", _error_text(error),
                                               _chosen({}, metrics),
                                               time.perf_counter() - started)
            continue
        simulation = item.setup.simulation
        together = (item.signal.size, simulation.integrator, simulation.control_step,
                    simulation.substeps)
        groups.setdefault(together, []).append(item)
    for items in groups.values():
        for outcome in _run_rigs_together(run, metrics, items):
            outcomes[outcome.index] = outcome
    return [outcomes[case.index] for case in cases]


def _robot_case(run: RunSpec, metrics: tuple[str, ...], case: Case,
                folder: Path) -> tuple[dict[str, float], str]:
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.simulation import RobotSimulation

    options = parse_run_options(run.kind, case.run_options, case.seed)
    parameters = load_robot(run.params, [*run.overrides, *case.overrides])
    configuration = options.get("configuration", "quadruped")
    robot = build_robot(parameters, configuration, options["environment"], options["seed"])
    simulation = RobotSimulation(robot)
    if run.kind == "robot-stand":
        from pneumaquad.robot.experiment import run_phases
        from pneumaquad.robot.scenarios import stand_up_phases

        phases = stand_up_phases(simulation, hold=options["hold"], posture=options["posture"])
        outcome = run_phases(simulation, phases, folder, f"study case {case.index}: stand")
        summary = outcome.summary
    else:
        from pneumaquad.locomotion.walk_run import run_walk

        walk = run_walk(simulation, walk_settings(options), folder,
                        f"study case {case.index}: walk")
        outcome, summary = walk.run, walk.run.summary
    if outcome.interrupted:
        raise CaseInterruptedError(f"case {case.index} was interrupted")
    return _chosen(flat_figures(summary), metrics), _reasons(summary, run.kind)


#: The run options of a walk that are fields of its settings.
WALK_FIELDS = ("distance", "speed", "heading", "period", "duty_factor")


def walk_settings(options: Mapping[str, Any]) -> Any:
    """The :class:`pneumaquad.locomotion.walking.WalkSettings` of a walk's run options
    (SI; an option left out keeps the library's default).

    Raises
    ------
    ParameterError
        Naming ``run.<option>`` when a setting is out of its range.
    """
    import dataclasses

    from pneumaquad.locomotion.walk_run import WalkSettingsError, check_walk_settings
    from pneumaquad.locomotion.walking import WalkSettings

    changes = {name: options[name] for name in WALK_FIELDS if options.get(name) is not None}
    settings = dataclasses.replace(WalkSettings(), **changes)
    try:
        check_walk_settings(settings)
    except WalkSettingsError as error:
        raise ParameterError([Problem(f"run.{field}", getattr(settings, field), str(error))
                              for field in error.fields]) from None
    return settings


def _robot_batch(run: RunSpec, metrics: tuple[str, ...], cases: Sequence[Case],
                 runs_folder: Path | None) -> list[CaseOutcome]:
    outcomes = []
    for case in cases:
        started = time.perf_counter()
        kept = runs_folder / f"case-{case.index:06d}" if runs_folder is not None else None
        folder = kept if kept is not None else Path(tempfile.mkdtemp(prefix="pneumaquad-case-"))
        try:
            # a folder read once and removed is scratch: no CSV, no plots
            with scratch_run_folders() if kept is None else contextlib.nullcontext():
                figures, note = _robot_case(run, metrics, case, folder)
            outcome = CaseOutcome(case.index, "ok", "", figures, note=note)
        except CaseInterruptedError:
            raise
        except Exception as error:  # a case's own problem: recorded, the batch goes on
            outcome = CaseOutcome(case.index, "failed", _error_text(error),
                                  _chosen({}, metrics))
        finally:
            if kept is None:
                shutil.rmtree(folder, ignore_errors=True)
        outcome.wall_time = time.perf_counter() - started
        outcome.run_folder = str(kept) if kept is not None else ""
        outcomes.append(outcome)
    return outcomes


def run_batch(run: RunSpec, metrics: Sequence[str], cases: Sequence[Case],
              runs_folder: str | None = None) -> list[CaseOutcome]:
    """Run ``cases`` of the base run ``run`` and collect ``metrics`` of each.

    Parameters
    ----------
    run : RunSpec
    metrics : sequence of str
        Summary figure names (nested ones joined with dots); a figure a case's summary
        lacks is NaN.
    cases : sequence of Case
    runs_folder : str, optional
        Robot cases keep their run folder under it (``case-000012``); else a temporary
        folder is removed after the case.

    Returns
    -------
    list of CaseOutcome
        One per case, in order.

    Raises
    ------
    CaseInterruptedError
        Ctrl-C reached a case; nothing of the batch is returned.
    """
    if run.is_rig:
        return _rig_batch(run, tuple(metrics), cases)
    return _robot_batch(run, tuple(metrics), cases, Path(runs_folder) if runs_folder else None)


def warm_up(kind: str) -> None:
    """Load a worker's code once, before its first case: a rig worker's compiled code (a
    short rig run); a robot worker's MuJoCo and robot modules (its compiled code loads in
    its first case)."""
    if kind.startswith("rig-"):
        setup = load_rig("thesis-rig")
        simulate_rig(setup, np.full(5, setup.actuator.valve.offset_voltage),
                     closed_loop=False)
    else:
        import pneumaquad.locomotion.walk_run
        import pneumaquad.robot.simulation  # noqa: F401
