"""The robot recording is produced from one table per group: header and value of a column
come from the same entry, so a column added there appears in both."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.params import load_robot
from pneumaquad.robot import recording
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.simulation import RobotSimulation


@pytest.fixture(scope="module")
def simulation() -> RobotSimulation:
    sim = RobotSimulation(build_robot(load_robot("crr-quadruped"), configuration="fixed"))
    pose = np.tile(np.radians([0.0, -30.0, 60.0]), 4)
    sim.set_pose(pose)
    sim.command_angles(pose)
    sim.step(20)
    return sim


def test_headers_and_row_have_one_entry_per_column(simulation: RobotSimulation) -> None:
    columns = recording.recording_columns(simulation)
    row = recording.recording_row(simulation, simulation.reference_angles)
    robot = simulation.robot
    expected = (1 + len(robot.joint_names) * len(recording.JOINT_COLUMNS)
                + len(recording.THORAX_COLUMNS) + len(robot.legs) * len(recording.FOOT_COLUMNS)
                + len(recording.BODY_COLUMNS))
    assert len(columns) == row.size == expected
    assert len(set(columns)) == len(columns)


def test_a_column_added_to_a_table_appears_in_header_and_row(
    simulation: RobotSimulation, monkeypatch: pytest.MonkeyPatch
) -> None:
    extra = recording.Column("chamber pressure difference", "Pa",
                             lambda row: row.simulation.state["cap_pressure"]
                             - row.simulation.state["rod_pressure"])
    monkeypatch.setattr(recording, "JOINT_COLUMNS", (*recording.JOINT_COLUMNS, extra))
    columns = recording.recording_columns(simulation)
    row = dict(zip(columns, recording.recording_row(simulation, simulation.reference_angles),
                   strict=True))
    joint = simulation.robot.joint_names[2]
    index = 2
    assert row[f"{joint} chamber pressure difference [Pa]"] == pytest.approx(
        simulation.state["cap_pressure"][index] - simulation.state["rod_pressure"][index])
    assert row[f"{joint} cap pressure [Pa]"] == simulation.state["cap_pressure"][index]


def test_every_header_carries_an_si_unit() -> None:
    tables = (recording.JOINT_COLUMNS, recording.THORAX_COLUMNS, recording.FOOT_COLUMNS,
              recording.BODY_COLUMNS)
    units = {column.unit for table in tables for column in table}
    assert units <= {"rad", "rad/s", "m", "m/s", "V", "Pa", "N", "kg", "NL", "-"}
