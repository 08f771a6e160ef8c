"""Reading a run folder (rig or robot) for a report.

A run folder holds ``parameters.toml`` (resolved, SI), ``recording.parquet`` and/or
``recording.csv``, ``summary.json`` and, for robot runs, ``model.xml``, ``trajectory.npz``
and plots. Rig files have a ``[rig]`` table, robot files a ``[leg]`` table; that decides
which loader validates them.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from pneumaquad.io.recording import read_recording
from pneumaquad.params import (
    JOINT_NAMES,
    ActuatorParameters,
    ParameterError,
    RigSetup,
    RobotParameters,
    load_actuator,
    load_rig,
    load_robot,
)

__all__ = ["ReportError", "RunFolder", "detect_run_kind", "load_run_folder"]

RunKind = Literal["rig", "robot"]


class ReportError(ValueError):
    """A run folder (or report input) that cannot be reported on; the message says why."""


@dataclass(frozen=True)
class RunFolder:
    """A loaded run folder.

    Attributes
    ----------
    path : Path
        The folder.
    kind : {"rig", "robot"}
        Which simulator wrote it.
    parameters : RigSetup or RobotParameters
        The validated resolved parameters (SI).
    actuators : dict of str to ActuatorParameters
        Label → actuator parameters: ``{"rig": ...}`` for a rig run, joint type
        (``"alpha"``, ``"beta"``, ``"gamma"``) → its set for a robot run (sets that could
        not be loaded are left out and listed in ``notes``).
    recording : dict of str to numpy.ndarray
        Columns ``"quantity [unit]"`` in SI.
    summary : dict
        Contents of ``summary.json`` (empty if absent).
    notes : list of str
        Things the report should mention (missing optional files, unloadable sets).
    """

    path: Path
    kind: RunKind
    parameters: RigSetup | RobotParameters
    actuators: dict[str, ActuatorParameters]
    recording: dict[str, np.ndarray]
    summary: dict[str, Any]
    notes: list[str] = field(default_factory=list)

    @property
    def description(self) -> str:
        """The run's description from its summary, or the folder name."""
        return str(self.summary.get("description", self.path.name))

    @property
    def set_name(self) -> str:
        """Name of the parameter set the run used (``meta.name``)."""
        if isinstance(self.parameters, RigSetup):
            return self.parameters.actuator.meta.name
        return self.parameters.meta.name


def detect_run_kind(raw: dict[str, Any]) -> RunKind:
    """``"rig"`` for a parameter table with ``[rig]``, ``"robot"`` for one with ``[leg]``.

    Raises
    ------
    ReportError
        When neither table is there.
    """
    if "rig" in raw:
        return "rig"
    if "leg" in raw:
        return "robot"
    raise ReportError(
        "parameters.toml has neither a [rig] table (rig run) nor a [leg] table (robot run)"
    )


def _read_parameters(path: Path) -> tuple[RunKind, RigSetup | RobotParameters]:
    file = path / "parameters.toml"
    if not file.is_file():
        raise ReportError(f"{path} is not a run folder: it has no parameters.toml")
    try:
        raw = tomllib.loads(file.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise ReportError(f"{file} is not valid TOML: {error}") from None
    kind = detect_run_kind(raw)
    return kind, (load_rig(file) if kind == "rig" else load_robot(file))


def _read_summary(path: Path, notes: list[str]) -> dict[str, Any]:
    file = path / "summary.json"
    if not file.is_file():
        notes.append("summary.json is missing: no metrics table.")
        return {}
    try:
        summary = json.loads(file.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ReportError(f"{file} is not valid JSON: {error}") from None
    if not isinstance(summary, dict):
        raise ReportError(f"{file} should hold a JSON object, not {type(summary).__name__}")
    return summary


def _read_recording(path: Path) -> dict[str, np.ndarray]:
    try:
        recording = read_recording(path)
    except FileNotFoundError:
        raise ReportError(f"{path} has no recording (recording.parquet or recording.csv)") from None
    except (OSError, ValueError) as error:
        raise ReportError(f"the recording in {path} cannot be read: {error}") from None
    if "time [s]" not in recording:
        raise ReportError(f"the recording in {path} has no 'time [s]' column")
    return recording


def _robot_actuators(
    parameters: RobotParameters, notes: list[str]
) -> dict[str, ActuatorParameters]:
    actuators = {}
    for joint in JOINT_NAMES:
        name = getattr(parameters.actuators, joint)
        try:
            actuators[joint] = load_actuator(name)
        except ParameterError as error:
            notes.append(
                f"actuator set {name!r} of the {joint} joints could not be loaded "
                f"(no model curves for it): {error}"
            )
    return actuators


def load_run_folder(path: Path) -> RunFolder:
    """Load a rig or robot run folder.

    Parameters
    ----------
    path : Path
        The run folder.

    Returns
    -------
    RunFolder

    Raises
    ------
    ReportError
        If the folder does not exist or lacks ``parameters.toml`` or a recording, or a
        file is malformed.
    ParameterError
        If ``parameters.toml`` does not validate.
    """
    path = Path(path)
    if not path.exists():
        raise ReportError(f"run folder {path} does not exist")
    if not path.is_dir():
        raise ReportError(f"{path} is not a folder (expected a run folder)")
    notes: list[str] = []
    kind, parameters = _read_parameters(path)
    recording = _read_recording(path)
    summary = _read_summary(path, notes)
    if isinstance(parameters, RigSetup):
        actuators = {"rig": parameters.actuator}
    else:
        actuators = _robot_actuators(parameters, notes)
    return RunFolder(path, kind, parameters, actuators, recording, summary, notes)
