"""Golden trajectories: a short rig run and a short robot run against stored recordings.

A change that reorganises code must not change what it computes. These runs cover the
rig kernel (closed-loop sine, thesis rig, Stribeck-tanh friction, underlapped valve) and
the coupled robot (fixed thorax, all 12 joints closed loop, a 20° front-right gamma step:
MuJoCo, linkages, PID, kernel, seal friction). Their recordings (every 10th control step)
are compared with files in ``tests/data/golden``.

Tolerance: relative 1e-9 of each column's span (plus 1e-12 absolute). The runs are
deterministic on one machine (bit-identical); the margin is for other CPUs, where the
compiled code may fuse multiply-adds differently (differences near 1e-15, which these
short, non-chaotic runs do not amplify past 1e-10). To accept a deliberate change of the
physics, regenerate with ``PNEUMAQUAD_REGENERATE_GOLDEN=1 pytest tests/test_golden.py``
and say why in the commit.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.params import load_rig, load_robot
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.recording import recording_columns, recording_row
from pneumaquad.robot.simulation import RobotSimulation

FOLDER = Path(__file__).parent / "data" / "golden"
REGENERATE = os.environ.get("PNEUMAQUAD_REGENERATE_GOLDEN") == "1"
RELATIVE = 1e-9


def _compare(name: str, columns: list[str], rows: np.ndarray) -> None:
    path = FOLDER / f"{name}.csv"
    if REGENERATE:
        np.savetxt(path, rows, delimiter=",", header=",".join(columns), comments="",
                   fmt="%.17g")
        pytest.skip(f"regenerated {path.name}")
    stored_columns = path.read_text().split("\n", 1)[0].split(",")
    assert stored_columns == columns, "the recording's columns changed"
    stored = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert stored.shape == rows.shape
    missing = np.isnan(stored)
    assert np.array_equal(missing, np.isnan(rows)), "not-a-number cells moved"
    stored, rows = np.where(missing, 0.0, stored), np.where(missing, 0.0, rows)
    span = np.ptp(stored, axis=0)
    tolerance = RELATIVE * span + 1e-12
    worst = np.abs(rows - stored) - tolerance
    column = int(np.argmax(worst.max(axis=0)))
    assert worst.max() <= 0.0, (
        f"{columns[column]} differs from the golden run by "
        f"{np.abs(rows - stored)[:, column].max():.3g} (tolerance {tolerance[column]:.3g})")


def test_rig_closed_loop_sine_matches_the_golden_run() -> None:
    setup = load_rig("thesis-rig")
    dt = setup.simulation.control_step
    reference = signals.sine(0.022, 0.01, 1.0, 1.0, dt)
    recording = simulate_rig(setup, reference, closed_loop=True).recording
    columns = list(recording)
    rows = np.column_stack([recording[name] for name in columns])[::10]
    _compare("rig-closed-loop-sine", columns, rows)


def test_robot_gamma_step_matches_the_golden_run() -> None:
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
    pose = np.tile(np.radians([0.0, -30.0, 60.0]), 4)
    simulation.set_pose(pose)
    target = pose.copy()
    target[5] += np.radians(20.0)
    simulation.command_angles(target)
    rows = []
    for _ in range(40):  # 0.4 s
        simulation.step(10)
        rows.append(recording_row(simulation, simulation.reference_angles))
    _compare("robot-gamma-step", list(recording_columns(simulation)), np.array(rows))
