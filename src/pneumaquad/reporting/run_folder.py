"""A run folder (rig or robot) loaded for a report.

The files are read by :func:`pneumaquad.io.run_folder.read_run_folder` (the one reader of
the layout, docs/run-folder.md); here ``parameters.toml`` is validated with the loader its
kind asks for (a ``[rig]`` table: rig run, a ``[leg]`` table: robot run) and the actuator
sets of a robot run are loaded for the model curves.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.run_folder import RunFolder, RunFolderError, RunKind, read_run_folder
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

__all__ = ["LoadedRun", "ReportError", "load_run_folder"]


class ReportError(ValueError):
    """A run folder (or report input) that cannot be reported on; the message says why."""


@dataclass(frozen=True)
class LoadedRun:
    """A run folder with its parameters validated.

    Attributes
    ----------
    folder : RunFolder
        The files as read (summary, recording, timing, format version).
    parameters : RigSetup or RobotParameters
        The validated resolved parameters (SI).
    actuators : dict of str to ActuatorParameters
        Label → actuator parameters: ``{"rig": ...}`` for a rig run, joint type
        (``"alpha"``, ``"beta"``, ``"gamma"``) → its set for a robot run (sets that could
        not be loaded are left out and listed in ``notes``).
    notes : list of str
        Things the report should mention (missing optional files, unloadable sets).
    """

    folder: RunFolder
    parameters: RigSetup | RobotParameters
    actuators: dict[str, ActuatorParameters]
    notes: list[str] = field(default_factory=list)

    @property
    def path(self) -> Path:
        """The run folder."""
        return self.folder.path

    @property
    def kind(self) -> RunKind:
        """``"rig"`` or ``"robot"``."""
        return self.folder.kind

    @property
    def recording(self) -> dict[str, np.ndarray]:
        """Columns ``"quantity [unit]"`` in SI."""
        return self.folder.recording

    @property
    def summary(self) -> dict[str, Any]:
        """Contents of ``summary.json`` (empty if absent)."""
        return self.folder.summary

    @property
    def timing(self) -> dict[str, Any] | None:
        """``timing.json`` of a networked run."""
        return self.folder.timing

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


def _robot_actuators(
    parameters: RobotParameters, notes: list[str]
) -> dict[str, ActuatorParameters]:
    actuators = {}
    for joint in JOINT_NAMES:
        name = getattr(parameters.actuators, joint)
        try:
            actuators[joint] = load_actuator(name, parameters.actuators.actuator_overrides())
        except ParameterError as error:
            notes.append(
                f"actuator set {name!r} of the {joint} joints could not be loaded "
                f"(no model curves for it): {error}"
            )
    return actuators


def load_run_folder(path: Path) -> LoadedRun:
    """Load a rig or robot run folder and validate its parameters.

    Raises
    ------
    ReportError
        If the folder does not exist or lacks ``parameters.toml`` or a recording, a file
        is malformed, or it was written in a newer run folder format.
    ParameterError
        If ``parameters.toml`` does not validate.
    """
    try:
        folder = read_run_folder(Path(path))
    except RunFolderError as error:
        raise ReportError(str(error)) from None
    notes = list(folder.notes)
    loader = load_rig if folder.kind == "rig" else load_robot
    parameters = loader(folder.parameters_file)
    if isinstance(parameters, RigSetup):
        actuators = {"rig": parameters.actuator}
    else:
        actuators = _robot_actuators(parameters, notes)
    return LoadedRun(folder, parameters, actuators, notes)
