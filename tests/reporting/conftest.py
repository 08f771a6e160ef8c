"""Short rig and robot run folders shared by the report tests (built once per session)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pneumaquad.demo.reports import write_lab_style_csv
from pneumaquad.params import load_rig, load_robot
from pneumaquad.reporting.rig_experiment import run_rig_experiment
from pneumaquad.rig import signals

INCH = 0.0254
PSI = 6894.757293168361
#: Description with markup characters: the report must show it escaped.
RIG_DESCRIPTION = 'step train <b>bold</b> & "quoted"'
#: Levels [m] and dwell [s] of the closed-loop step train (two steps, 2.1 s).
LEVELS = (0.4 * INCH, 1.4 * INCH, 0.8 * INCH)
DWELL = 0.7


@pytest.fixture(scope="session")
def rig_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 2.1 s closed-loop step train of the thesis rig."""
    folder = tmp_path_factory.mktemp("runs") / "rig-steps"
    setup = load_rig("thesis-rig")
    reference = signals.step_train(LEVELS, DWELL, setup.simulation.control_step)
    run_rig_experiment(setup, folder, reference, True, RIG_DESCRIPTION)
    return folder


@pytest.fixture(scope="session")
def robot_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Front-right gamma following the fast sine for 0.5 s after a 0.2 s settle."""
    from pneumaquad.reporting.robot_plots import plot_joints
    from pneumaquad.robot.builder import build_robot
    from pneumaquad.robot.experiment import run_phases
    from pneumaquad.robot.scenarios import leg_validation_phases
    from pneumaquad.robot.simulation import RobotSimulation

    folder = tmp_path_factory.mktemp("runs") / "leg-gamma"
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
    phases = leg_validation_phases(simulation, "gamma", "fast-sine", settle=0.2)
    phases[-1].duration = 0.5
    run = run_phases(simulation, phases, folder, "front-right gamma: fast-sine (short)")
    plot_joints(run.recording, ["front_right_gamma"], folder / "joints.png")
    return folder


def write_measured_csv(
    recording: dict[str, np.ndarray],
    folder: Path,
    shift: float = 0.0,
    atmosphere: float = 101325.0,
) -> tuple[Path, Path]:
    """Write a recording as lab-style CSV (ms, in, psig) plus its TOML mapping, no noise.

    ``shift`` [s] delays the 'measured' signals: measured(t) = simulated(t - shift).
    """
    return write_lab_style_csv(recording, folder, shift, position_noise=0.0,
                               pressure_noise=0.0, name="measured", atmosphere=atmosphere)
