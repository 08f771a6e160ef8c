"""Run-folder output of a networked peer: robot recording, packet log, timing figures.

:class:`NetworkRecording` buffers recording rows and hands them to the run folder's
recorder in blocks (``recording.csv`` stays readable while the run goes on;
``recording.parquet`` on close). :func:`write_network_files` writes ``packets.parquet``,
``timing.json`` (:func:`~pneumaquad.network.timing.timing_summary` plus the caller's
figures), ``rtt.png`` and ``timeline.png``; :func:`write_run_description` the parameters,
model and summary. Every file of the run folder goes through
:class:`~pneumaquad.io.run_folder.RunFolderWriter` (docs/run-folder.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.run_folder import RunFolderWriter
from pneumaquad.network.packet_log import PacketLog
from pneumaquad.network.timing import timing_summary
from pneumaquad.robot.builder import RobotJoints, RobotModel

__all__ = ["NetworkRecording", "write_network_files", "write_run_description"]

_BLOCK_ROWS = 200


class NetworkRecording:
    """Buffered robot recording of a networked run.

    Parameters
    ----------
    folder
        Run folder.
    columns
        Column names (``quantity [unit]``).
    """

    def __init__(self, folder: Path, columns: Sequence[str]) -> None:
        self.recorder = RunFolderWriter(folder).recorder(columns)
        self.width = len(columns)
        self._buffer = np.empty((_BLOCK_ROWS, self.width))
        self._rows = 0

    def append(self, row: np.ndarray) -> None:
        """Buffer one row; a full buffer is written (and flushed) to ``recording.csv``."""
        self._buffer[self._rows] = row
        self._rows += 1
        if self._rows == _BLOCK_ROWS:
            self.flush()

    def flush(self) -> None:
        """Write the buffered rows."""
        if self._rows:
            self.recorder.append(self._buffer[: self._rows])
            self._rows = 0

    def close(self) -> None:
        """Flush and write ``recording.parquet`` (idempotent)."""
        if not self.recorder.closed:
            self.flush()
            self.recorder.close()


def write_network_files(folder: Path, log: PacketLog, control_step: float,
                        extra: Mapping[str, Any], plots: bool = True) -> dict[str, Any]:
    """Write ``packets.parquet``, ``timing.json`` and the two plots into ``folder``.

    Parameters
    ----------
    folder
        Run folder.
    log
        The peer's packet log.
    control_step
        Nominal exchange period [s].
    extra
        More figures for ``timing.json`` (counters, jitter statistics, ...).
    plots
        Draw ``rtt.png`` and ``timeline.png``.

    Returns
    -------
    dict
        The content of ``timing.json``.
    """
    folder = Path(folder)
    writer = RunFolderWriter(folder)
    log.write(writer.packets_path)
    summary = dict(timing_summary(log, control_step)) | dict(extra)
    writer.write_timing(summary)
    if plots and len(log):
        from pneumaquad.network.timing_plots import plot_packet_timeline, plot_rtt_histogram

        plot_rtt_histogram(log, folder / "rtt.png", deadline=control_step)
        plot_packet_timeline(log, control_step, folder / "timeline.png")
    return summary


def write_run_description(folder: Path, robot: RobotJoints,
                          summary: Mapping[str, Any]) -> None:
    """Write ``parameters.toml``, ``model.xml`` and ``summary.json`` of a networked run, so
    that ``pneumaquad report`` and ``pneumaquad video`` read it like any robot run.

    ``model.xml`` comes from a built robot (the dynamics side); the actuator side holds
    the joints only (:func:`pneumaquad.robot.builder.robot_joints`) and writes none."""
    writer = RunFolderWriter(folder)
    writer.write_parameters(robot.parameters)
    if isinstance(robot, RobotModel):
        writer.write_model(robot.to_xml())
    writer.write_summary(summary)
