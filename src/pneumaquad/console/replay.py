"""Replay of a robot run folder in the console, and the static stability margin.

A run folder (``pneumaquad robot stand/walk ... -o FOLDER``, docs/run-folder.md) holds
``model.xml`` (the compiled MJCF), ``trajectory.npz`` (``time`` (T,), ``qpos`` (T, nq) at
the recording rate) and the recording (:func:`pneumaquad.io.run_folder.read_recording`).
:class:`ReplayRun` loads it; :meth:`ReplayRun.show` puts the nearest trajectory sample
into its own :class:`mujoco.MjData` (``mj_forward``) for the scene, and
:meth:`ReplayRun.row_at` finds the recording row nearest in time for the readouts.

:func:`static_stability` computes the static stability margin of a live simulation from
the feet in contact (normal force above :data:`CONTACT_FORCE` N) and the centre of mass,
with :mod:`pneumaquad.gait.stability`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from pneumaquad.gait.stability import STANCE_FORCE, loaded_support
from pneumaquad.io.run_folder import (
    MODEL_NAME,
    TRAJECTORY_NAME,
    RunFolderVersionError,
    read_recording,
)
from pneumaquad.robot.simulation import RobotSimulation

__all__ = ["CONTACT_FORCE", "ReplayError", "ReplayRun", "Stability", "static_stability"]

#: A foot is in stance when its normal contact force exceeds this [N].
CONTACT_FORCE = STANCE_FORCE


class ReplayError(ValueError):
    """A folder that cannot be replayed (missing or inconsistent files)."""


@dataclass
class Stability:
    """Support polygon, centre-of-mass projection and static stability margin.

    Attributes
    ----------
    polygon : ndarray (m, 2)
        Support polygon of the stance feet [m], counter-clockwise (m = 0: no support).
    com : ndarray (2,)
        Ground projection of the centre of mass [m] (NaN when unknown).
    margin : float
        Static stability margin [m]: positive inside the polygon, NaN without support.
    height : float
        Height at which to draw the polygon [m] (mean height of the stance feet).
    """

    polygon: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    com: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    margin: float = float("nan")
    height: float = 0.0


def _stability(feet: np.ndarray, forces: np.ndarray, com: np.ndarray,
               margin: float | None = None) -> Stability:
    feet = np.asarray(feet, dtype=float)
    com = np.asarray(com, dtype=float)
    polygon, computed = loaded_support(feet, forces, com)
    margin = computed if margin is None else margin
    if not polygon.size:
        return Stability(com=com, margin=float(margin))
    stance = np.asarray(forces) > STANCE_FORCE
    height = float(np.mean(feet[stance, 2])) if feet.shape[1] > 2 else 0.0
    return Stability(polygon, com, float(margin), height)


def static_stability(simulation: RobotSimulation) -> Stability:
    """Stability of the simulation's current state (feet with a normal force > 1 N)."""
    return _stability(simulation.foot_positions(), simulation.foot_normal_forces(),
                      simulation.data.subtree_com[0, :2].copy())


class ReplayRun:
    """A loaded run folder: model, trajectory, recording.

    Parameters
    ----------
    folder : Path
        The run folder.

    Raises
    ------
    ReplayError
        Without ``model.xml`` or ``trajectory.npz``, or when they do not match.
    """

    def __init__(self, folder: Path | str) -> None:
        folder = Path(folder).expanduser()
        if not folder.is_dir():
            raise ReplayError(f"{folder}: not a folder")
        missing = [n for n in (MODEL_NAME, TRAJECTORY_NAME) if not (folder / n).is_file()]
        if missing:
            raise ReplayError(f"{folder}: not a run folder (no {' and no '.join(missing)})")
        try:
            self.model = mujoco.MjModel.from_xml_path(str(folder / MODEL_NAME))
        except ValueError as error:
            raise ReplayError(f"{folder / MODEL_NAME}: {error}") from error
        try:
            with np.load(folder / TRAJECTORY_NAME) as trajectory:
                self.times = np.asarray(trajectory["time"], dtype=float)
                self.qpos = np.asarray(trajectory["qpos"], dtype=float)
        except (OSError, KeyError, ValueError) as error:
            raise ReplayError(f"{folder / TRAJECTORY_NAME}: unreadable ({error})") from error
        if self.qpos.ndim != 2 or self.qpos.shape != (len(self.times), self.model.nq):
            raise ReplayError(f"{folder / TRAJECTORY_NAME}: qpos {self.qpos.shape} does not "
                              f"match {len(self.times)} samples of nq = {self.model.nq}")
        if len(self.times) == 0:
            raise ReplayError(f"{folder / TRAJECTORY_NAME}: no samples")
        self.folder = folder
        self.data = mujoco.MjData(self.model)
        try:
            self.recording: dict[str, np.ndarray] | None = read_recording(folder)
        except RunFolderVersionError as error:
            raise ReplayError(str(error)) from error
        except (OSError, ValueError):
            self.recording = None
        self.record_times = (None if self.recording is None
                             else np.asarray(self.recording["time [s]"], dtype=float))
        self.legs = [] if self.recording is None else [
            name.removesuffix(" foot normal force [N]") for name in self.recording
            if name.endswith(" foot normal force [N]")
        ]
        self.joint_names = [name for name in (
            mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, j)
            for j in range(self.model.njnt)
            if self.model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
        ) if mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE,
                               f"{name}_barrel_pivot") >= 0]

    @property
    def joint_count(self) -> int:
        """Number of cylinder-driven joints (for :class:`.scene.RobotScene`)."""
        return len(self.joint_names)

    @property
    def duration(self) -> float:
        """Time of the last trajectory sample [s]."""
        return float(self.times[-1])

    def index_at(self, time: float) -> int:
        """Index of the trajectory sample nearest to ``time`` [s]."""
        return _nearest(self.times, time)

    def row_at(self, time: float) -> int | None:
        """Index of the recording row nearest to ``time`` [s] (None without recording)."""
        return None if self.record_times is None else _nearest(self.record_times, time)

    def show(self, time: float) -> int:
        """Put the sample nearest ``time`` into :attr:`data` (``mj_forward``); its index."""
        index = self.index_at(time)
        self.data.qpos[:] = self.qpos[index]
        self.data.qvel[:] = 0.0
        mujoco.mj_forward(self.model, self.data)
        return index

    def value(self, column: str, row: int | None, default: float = float("nan")) -> float:
        """Recording value of ``column`` at ``row`` (``default`` when absent)."""
        if row is None or self.recording is None or column not in self.recording:
            return default
        return float(self.recording[column][row])

    def stability(self, row: int | None) -> Stability:
        """Stability at recording ``row``: margin as recorded, polygon from the feet."""
        if row is None or not self.legs:
            return Stability()
        feet = np.array([[self.value(f"{leg} foot {axis} [m]", row) for axis in "xyz"]
                         for leg in self.legs])
        forces = np.array([self.value(f"{leg} foot normal force [N]", row)
                           for leg in self.legs])
        com = np.array([self.value("centre of mass x [m]", row),
                        self.value("centre of mass y [m]", row)])
        return _stability(feet, np.nan_to_num(forces), com,
                          margin=self.value("stability margin [m]", row))


def _nearest(times: np.ndarray, time: float) -> int:
    index = int(np.searchsorted(times, time))
    if index <= 0:
        return 0
    if index >= len(times):
        return len(times) - 1
    return index if times[index] - time < time - times[index - 1] else index - 1
