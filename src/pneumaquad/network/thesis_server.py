"""A dynamics server that speaks the thesis's own datagrams (App. C.2.4), for old clients.

The thesis's Simulink model and SrLib exchanged 21 float64 values per datagram, with no
header (:mod:`pneumaquad.network.thesis`). This server does what SrLib's control loop did
(``User_CBFunc_ControlLoop``, listing lines 1-18): on each received command it applies
the front-right (R1) alpha, beta, gamma torques from L11..L13, steps the dynamics once
(lockstep, like SrLib's Receive-Compute-Send), and answers with the R1 joint angles and
velocities, the thorax orientation, the echoed ``time_packet``, its send counter and the
simulation time.

SrLib drove the other three legs by position (``SetHapCommand`` into its internal
proportional controller, line 6-8); here they are held by a joint-space PD torque
(``hold_stiffness``, ``hold_damping``) at their initial posture, and the rear-left leg
follows L21..L23 as in the listing. Datagrams that are not exactly 168 bytes of finite
values are dropped and counted by reason.
"""

from __future__ import annotations

import select
import socket
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.io.run_folder import RunFolderWriter
from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.endpoint import DEFAULT_HOST, Address
from pneumaquad.network.run_output import NetworkRecording, write_run_description
from pneumaquad.network.thesis import THESIS_SIZE, decode_thesis_command, encode_thesis_state
from pneumaquad.network.wire import ProtocolError
from pneumaquad.robot.errors import SimulationDivergedError

__all__ = ["ThesisServer"]


class ThesisServer:
    """Lockstep dynamics server in the thesis's 21-double layout (torque commands for R1).

    Parameters
    ----------
    side : DynamicsSide
        A torque-mode dynamics side (``command_kind="torque"``).
    bind : (str, int)
        Local address; 127.0.0.1 unless another is asked for.
    peer : (str, int), optional
        Accept datagrams from this address only.
    hold_stiffness, hold_damping : float
        PD gains holding the legs other than R1 [N m/rad], [N m s/rad].
    duration : float, optional
        Wall-clock limit [s].
    folder : Path, optional
        Run folder for ``recording.csv``/``.parquet`` and ``timing.json``.
    """

    def __init__(self, side: DynamicsSide, bind: Address = (DEFAULT_HOST, 0),
                 peer: Address | None = None, hold_stiffness: float = 30.0,
                 hold_damping: float = 1.0, duration: float | None = None,
                 folder: Path | None = None) -> None:
        if side.command_kind != "torque":
            raise ValueError("the thesis layout carries joint torques: use a torque-mode side")
        self.side = side
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.bind(bind)
        self.socket.setblocking(False)
        self.peer = peer
        self.duration = duration
        self.folder = None if folder is None else Path(folder)
        self.hold_stiffness = hold_stiffness
        self.hold_damping = hold_damping
        names = side.robot.joint_names
        self.front_right = np.array([names.index(f"front_right_{j}")
                                     for j in ("alpha", "beta", "gamma")])
        self.rear_left = np.array([names.index(f"rear_left_{j}")
                                   for j in ("alpha", "beta", "gamma")])
        robot = side.robot
        self.hold_angles = side.data.qpos[robot.qpos_address].copy()
        self.sent = 0
        self.steps = 0
        self.divergences = 0  # steps that diverged (the run then ends) [count]
        self.divergence: str | None = None
        self.dropped: Counter[str] = Counter()
        self._stop = False

    @property
    def address(self) -> Address:
        """Bound ``(host, port)``."""
        host, port = self.socket.getsockname()[:2]
        return host, port

    def stop(self) -> None:
        """Ask :meth:`run` to return after the current datagram."""
        self._stop = True

    def _torques(self, command_torques: np.ndarray, rear_left_angles: np.ndarray) -> np.ndarray:
        robot, data = self.side.robot, self.side.data
        targets = self.hold_angles.copy()
        targets[self.rear_left] = rear_left_angles
        angles = data.qpos[robot.qpos_address]
        velocities = data.qvel[robot.dof_address]
        torques = self.hold_stiffness * (targets - angles) - self.hold_damping * velocities
        torques[self.front_right] = command_torques
        return torques

    def handle(self, datagram: bytes) -> bytes | None:
        """One SrLib control-loop iteration for one datagram; the reply, or None if dropped."""
        if len(datagram) != THESIS_SIZE:
            self.dropped["truncated" if len(datagram) < THESIS_SIZE else "oversized"] += 1
            return None
        try:
            command = decode_thesis_command(datagram)
        except ProtocolError as error:
            self.dropped[error.reason] += 1
            return None
        self.side.apply(self._torques(command.torques, command.rear_left_angles))
        try:
            self.side.step()
        except SimulationDivergedError as error:
            # the side undid the step and engaged the safe state; the thesis layout has no
            # status field, so the run ends after this reply (of the last good state)
            self.divergences += 1
            self.divergence = str(error)
            self._stop = True
        else:
            self.steps += 1
        self.sent += 1
        robot, data = self.side.robot, self.side.data
        angles = data.qpos[robot.qpos_address][self.front_right]
        velocities = data.qvel[robot.dof_address][self.front_right]
        orientation = data.xmat[robot.thorax_id].reshape(3, 3)
        return encode_thesis_state(angles, velocities, orientation, command.time_packet,
                                   self.sent, self.side.time)

    def run(self, stop_request: Any = None) -> dict[str, Any]:
        """Serve until :meth:`stop`, ``duration``, ``stop_request.requested`` (Ctrl-C) or a
        KeyboardInterrupt; returns the summary (also written to ``timing.json``)."""
        recording = (None if self.folder is None
                     else NetworkRecording(self.folder, self.side.recording_columns()))
        started = time.perf_counter()
        foreign = 0
        try:
            while not self._stop and not (stop_request is not None and stop_request.requested):
                if self.duration is not None and time.perf_counter() - started > self.duration:
                    break
                if not select.select([self.socket], [], [], 0.05)[0]:
                    continue
                try:
                    datagram, source = self.socket.recvfrom(2048)
                except OSError:
                    self.dropped["socket error"] += 1
                    continue
                if self.peer is not None and (source[0], source[1]) != self.peer:
                    foreign += 1
                    continue
                reply = self.handle(datagram)
                if reply is None:
                    continue
                self.socket.sendto(reply, source)
                if recording is not None:
                    recording.append(self.side.recording_row())
        except KeyboardInterrupt:
            pass
        finally:
            if recording is not None:
                recording.close()
        summary = {
            "layout": "thesis App. C.2.4 (21 float64, no header)",
            "control steps [count]": self.steps,
            "simulated time [s]": self.side.time,
            "wall time [s]": time.perf_counter() - started,
            "foreign [count]": foreign,
            **{f"dropped {reason} [count]": count for reason, count in self.dropped.items()},
            "divergences [count]": self.divergences,
        }
        if self.divergence is not None:
            summary["error"] = self.divergence
        if self.folder is not None:
            RunFolderWriter(self.folder).write_timing(summary)
            write_run_description(self.folder, self.side.robot, summary)
        self.socket.close()
        return summary
