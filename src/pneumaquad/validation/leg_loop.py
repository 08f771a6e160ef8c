"""Closed-loop figures of the front-right leg as thesis 5.5.2 reports them.

Protocols (:func:`pneumaquad.robot.scenarios.leg_validation_phases`, fixed thorax, the
other two joints of the leg extended open loop for 2 s first):

* Sine: the ``fast-sine`` signal, 0.5 Hz, ±30 % of the joint's range about its middle,
  five cycles; the lag of the joint angle behind its reference is measured over the last
  four (:func:`pneumaquad.analysis.metrics.lag`). The thesis's gamma sine (Fig. 40) and
  beta fast sine (Fig. 42) print no frequency; one protocol serves both.
* Steps: the ``steps`` signal, eight levels across the range, 2 s each; the mean 10-90 %
  rise time and overshoot over the steps
  (:func:`pneumaquad.analysis.segmentation.metrics_per_step`), and the mean time constant
  of thesis eq (4.3.1) fitted to each step from its instant, as 4.3 did on the rig.
* Walking motion (5.5.2.4): :func:`pneumaquad.robot.scenarios.foot_cycle_phases` at slow,
  medium and fast rates; per joint the angle RMSE against the reference, the lag, the
  RMSE left once the reference is shifted by that lag, and the RMS of the error's part
  above 3 Hz (the oscillation the thesis's lower alpha gain removed).
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pneumaquad.analysis.filters import lowpass_filter
from pneumaquad.analysis.fits import fit_first_order
from pneumaquad.analysis.metrics import lag, rmse
from pneumaquad.analysis.segmentation import find_steps, metrics_per_step
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.experiment import run_phases
from pneumaquad.robot.scenarios import foot_cycle_phases, leg_validation_phases
from pneumaquad.robot.simulation import RobotSimulation

__all__ = [
    "OSCILLATION_CUTOFF",
    "FootCycleFigures",
    "JointFigures",
    "foot_cycle_figures",
    "foot_cycle_figures_of",
    "foot_cycle_tracks",
    "joint_figures",
]

#: Settling phase before the leg signals [s] (the scenario's default).
SETTLE = 2.0
#: Step-detection threshold on the joint reference [rad].
STEP_THRESHOLD = 0.01
#: Above this the tracking error of the walking motion counts as oscillation [Hz].
OSCILLATION_CUTOFF = 3.0


@dataclass(frozen=True)
class JointFigures:
    """Sine and step figures of one joint of the front-right leg.

    Attributes
    ----------
    joint : str
        ``alpha``, ``beta`` or ``gamma``.
    sine_lag : float
        Lag of the angle behind the fast-sine reference [s].
    sine_rmse : float
        Angle RMSE against the sine reference [deg].
    rise_time : float
        Mean 10-90 % rise time over the step train [s].
    time_constant : float
        Mean time constant of thesis eq (4.3.1) fitted to each step of the train [s].
    overshoot : float
        Mean overshoot over the step train [%].
    step_rmse : float
        Angle RMSE against the step reference [deg].
    """

    joint: str
    sine_lag: float
    sine_rmse: float
    rise_time: float
    time_constant: float
    overshoot: float
    step_rmse: float


@dataclass(frozen=True)
class FootCycleFigures:
    """Walking-motion figures of one joint (thesis 5.5.2.4).

    Attributes
    ----------
    joint : str
        Joint type.
    gain_scale : float
        The alpha PID gain scale of the run [-].
    rmse : float
        Angle RMSE against the reference [deg].
    lag : float
        Lag of the angle behind the reference [s].
    shifted_rmse : float
        RMSE against the reference delayed by ``lag`` [deg].
    oscillation : float
        RMS of the tracking error above :data:`OSCILLATION_CUTOFF` [deg].
    """

    joint: str
    gain_scale: float
    rmse: float
    lag: float
    shifted_rmse: float
    oscillation: float


def _simulation(params: str, overrides: Sequence[str]) -> RobotSimulation:
    robot = build_robot(load_robot(params, list(overrides)), "fixed", "flat", 0)
    return RobotSimulation(robot)


def _run_leg_signal(params: str, overrides: Sequence[str], joint: str,
                    signal: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time [s], angle and reference [rad] of the tested joint after the settling."""
    simulation = _simulation(params, overrides)
    with tempfile.TemporaryDirectory() as folder:
        run = run_phases(simulation, leg_validation_phases(simulation, joint, signal, SETTLE),
                         Path(folder) / "run", f"front-right {joint}: {signal}")
    time = run.recording["time [s]"]
    kept = time > SETTLE
    angle = run.recording[f"front_right_{joint} angle [rad]"][kept]
    reference = run.recording[f"front_right_{joint} reference [rad]"][kept]
    return time[kept], angle, reference


def _rmse_degrees(estimate: np.ndarray, reference: np.ndarray) -> float:
    """:func:`pneumaquad.analysis.metrics.rmse` of two angle series [rad], in degrees."""
    return float(np.degrees(rmse(estimate, reference)))


def joint_figures(joint: str, params: str = "crr-quadruped",
                  overrides: Sequence[str] = ()) -> JointFigures:
    """Fast-sine and step-train figures of the front-right ``joint``.

    Parameters
    ----------
    joint : str
        ``alpha``, ``beta`` or ``gamma``.
    params : str
        Robot parameter set (name or TOML path).
    overrides : sequence of str
        ``section.key=value`` overrides, as ``--set``.
    """
    time, angle, reference = _run_leg_signal(params, overrides, joint, "fast-sine")
    measured = time >= SETTLE + 2.0  # after the first 0.5 Hz cycle
    sine_lag = lag(time[measured], angle[measured], reference[measured], max_lag=0.5)
    sine_rmse = _rmse_degrees(angle, reference)
    time, angle, reference = _run_leg_signal(params, overrides, joint, "steps")
    steps = metrics_per_step(time, angle, reference, STEP_THRESHOLD)
    constants = []
    for segment in find_steps(time, reference, STEP_THRESHOLD):
        window = (time >= segment.start_time) & (time < segment.end_time)
        fit = fit_first_order(time[window], angle[window], start_time=segment.start_time)
        constants.append(fit.parameters["time constant [s]"])
    return JointFigures(
        joint=joint,
        sine_lag=sine_lag,
        sine_rmse=sine_rmse,
        rise_time=float(np.nanmean([s["rise time [s]"] for s in steps])),
        time_constant=float(np.mean(constants)),
        overshoot=float(np.nanmean([s["overshoot [%]"] for s in steps])),
        step_rmse=_rmse_degrees(angle, reference),
    )


def foot_cycle_tracks(gain_scale: float, params: str = "crr-quadruped",
                      overrides: Sequence[str] = ()
                      ) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """Run the walking motion of thesis 5.5.2.4 with the alpha gains scaled by
    ``gain_scale``; time [s] after the settling phase and, per joint of the front-right
    leg, its angle and reference [rad]."""
    settings = [*overrides, f"controller.alpha.gain_scale={gain_scale!r}"]
    simulation = _simulation(params, settings)
    phases = foot_cycle_phases(simulation)
    with tempfile.TemporaryDirectory() as folder:
        run = run_phases(simulation, phases, Path(folder) / "run", "foot cycle")
    time = run.recording["time [s]"]
    kept = time > phases[0].duration
    tracks = {joint: (run.recording[f"front_right_{joint} angle [rad]"][kept],
                      run.recording[f"front_right_{joint} reference [rad]"][kept])
              for joint in ("alpha", "beta", "gamma")}
    return time[kept], tracks


def foot_cycle_figures_of(time: np.ndarray, tracks: dict[str, tuple[np.ndarray, np.ndarray]],
                          gain_scale: float) -> list[FootCycleFigures]:
    """:class:`FootCycleFigures` of each joint of :func:`foot_cycle_tracks`'s output."""
    figures = []
    for joint, (angle, reference) in tracks.items():
        delay = lag(time, angle, reference, max_lag=0.5)
        shifted = np.interp(time - delay, time, reference)
        error = angle - reference
        smooth = lowpass_filter(time, error, OSCILLATION_CUTOFF)
        figures.append(FootCycleFigures(
            joint=joint,
            gain_scale=gain_scale,
            rmse=_rmse_degrees(angle, reference),
            lag=delay,
            shifted_rmse=_rmse_degrees(angle, shifted),
            oscillation=_rmse_degrees(error, smooth),
        ))
    return figures


def foot_cycle_figures(gain_scale: float, params: str = "crr-quadruped",
                       overrides: Sequence[str] = ()) -> list[FootCycleFigures]:
    """The walking motion of thesis 5.5.2.4 with the alpha gains scaled by ``gain_scale``;
    figures per joint of the front-right leg (:class:`FootCycleFigures`)."""
    time, tracks = foot_cycle_tracks(gain_scale, params, overrides)
    return foot_cycle_figures_of(time, tracks, gain_scale)
