"""The dynamics server: a :class:`DynamicsSide` behind a UDP endpoint.

Two modes (Daepp 2011, ch. 5.1: SrLib's loop was Receive - Compute - Send):

``"lockstep"``
    The dynamics steps once per new command and answers it with a ``STATE`` whose
    answered sequence is the command's. A command whose sender time (the simulation
    time at which it takes effect) lies before the current simulation time is a
    retransmission of one already applied: it is answered with the current ``STATE``
    without stepping, so a client that resends after a lost reply stays in step.
    Simulated time advances only with commands: there is no command timeout.
``"realtime"``
    Paced to the wall clock (``time.perf_counter``) at the control rate: every period
    the last command is applied, the dynamics steps and a ``STATE`` goes to the peer.
    After ``timeout`` s without a new command the safe state is engaged
    (``SAFE_STATE | COMMAND_TIMED_OUT`` in the ``STATE`` and in the ``network status
    [-]`` recording column) and the peer's sequence tracking is reset; the next
    command releases it and the next ``STATE`` carries ``RESYNCHRONISED``.

Both answer ``PING`` with ``PONG``, answer a ``HELLO`` with their own ``HELLO`` (joint
count and control step) and the current ``STATE`` (flagged ``RESYNCHRONISED``) without
stepping, and stop on ``BYE``, on :meth:`stop`, on ``stop_request.requested`` (Ctrl-C)
or after ``duration`` s of wall time. A ``HELLO`` whose joint count or control step is
invalid or not the server's is refused (counted as malformed ``bad_count`` and as a
refused HELLO) and answered with the server's ``HELLO`` only, so the peer can tell what
to use. Commands are limited to what the actuators can deliver
(:meth:`DynamicsSide.apply`); a ``STATE`` that follows a clamped command carries
``CLAMPED``. With a run
folder, the robot recording, ``packets.parquet``, ``timing.json``, ``rtt.png`` and
``timeline.png`` are written, also when the run is interrupted.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.endpoint import DEFAULT_HOST, Address, UdpEndpoint
from pneumaquad.network.protocol import encode_hello, encode_pong, encode_state
from pneumaquad.network.run_output import (
    NetworkRecording,
    write_network_files,
    write_run_description,
)
from pneumaquad.network.state import StatusFlag
from pneumaquad.network.timing import jitter_statistics
from pneumaquad.network.wire import Message, MessageType
from pneumaquad.robot.errors import SimulationDivergedError

__all__ = ["MODES", "DynamicsServer", "StopFlag"]

MODES = ("lockstep", "realtime")
_COMMAND_TYPE = {"valve": MessageType.VALVE_COMMAND, "force": MessageType.FORCE_COMMAND,
                 "torque": MessageType.TORQUE_COMMAND}
_IDLE_WAIT = 0.05  # [s] longest block in lockstep mode, to check stop and duration
_CATCH_UP_PERIODS = 10  # a realtime loop further behind than this restarts its schedule


class StopFlag(Protocol):
    """Anything with a boolean ``requested`` (e.g. ``pneumaquad.io.interruption.StopRequest``)."""

    requested: bool


class DynamicsServer:
    """Serve a :class:`DynamicsSide` over UDP.

    Parameters
    ----------
    side
        The dynamics.
    bind
        Local ``(host, port)``; 127.0.0.1 and a free port by default.
    peer
        Optional ``(host, port)`` filter: datagrams from elsewhere are dropped, counted.
    mode
        ``"lockstep"`` or ``"realtime"``.
    timeout
        Realtime: command silence before the safe state [s].
    duration
        Wall-clock run time limit [s]; ``None``: until ``BYE`` or :meth:`stop`.
    folder
        Run folder for the recording and the packet files; ``None``: nothing written.
    record_every
        Record one row every this many control steps.
    plots
        Draw ``rtt.png`` / ``timeline.png`` on close.
    """

    def __init__(self, side: DynamicsSide, bind: Address = (DEFAULT_HOST, 0),
                 peer: Address | None = None, mode: str = "lockstep", timeout: float = 0.1,
                 duration: float | None = None, folder: Path | None = None,
                 record_every: int = 1, plots: bool = True, busy_wait: float = 0.0) -> None:
        if mode not in MODES:
            raise ValueError(f"mode {mode!r} should be one of {MODES}")
        if not timeout > 0 or record_every < 1:
            raise ValueError("timeout must be > 0 and record_every >= 1")
        self.side = side
        self.mode = mode
        self.timeout = timeout
        self.duration = duration
        self.folder = None if folder is None else Path(folder)
        self.record_every = record_every
        self.plots = plots
        self.endpoint = UdpEndpoint(bind, peer, side.joint_count, busy_wait=busy_wait,
                                    hello_dimensions=(side.joint_count, side.control_step))
        self.command_type = _COMMAND_TYPE[side.command_kind]
        self.client: Address | None = None
        self.answered = -1
        self.steps = 0
        self.retransmissions = 0  # lockstep commands answered without stepping [count]
        self.wrong_commands = 0  # commands of another kind than served [count]
        self.timeouts = 0  # realtime safe-state engagements [count]
        self.divergences = 0  # steps that diverged (the run then ends) [count]
        self.divergence: str | None = None  # the divergence's message
        self.refused_hellos = 0  # HELLOs with other dimensions than the server's [count]
        self.wakeups: list[float] = []
        self._pending = StatusFlag.NONE  # one-shot flags for the next STATE
        self._timed_out = False
        self._last_command = 0.0
        self._stopping = False
        self._recording: NetworkRecording | None = None
        self.summary: dict[str, Any] = {}

    @property
    def address(self) -> Address:
        """Bound ``(host, port)``."""
        return self.endpoint.address

    def stop(self) -> None:
        """Ask :meth:`run` to return (thread-safe; takes effect within ~50 ms)."""
        self._stopping = True

    # --- status and replies --------------------------------------------------------------
    def status(self) -> StatusFlag:
        """Persistent status bits (safe state, timed out) without the one-shot ones."""
        flags = StatusFlag.NONE
        if self._timed_out:
            flags |= StatusFlag.COMMAND_TIMED_OUT
        if self.side.safe:
            flags |= StatusFlag.SAFE_STATE
        if self.side.diverged:
            flags |= StatusFlag.DIVERGED
        elif self.side.command_clamped:
            flags |= StatusFlag.CLAMPED
        return flags

    def _send_hello(self, address: Address) -> None:
        self.endpoint.send(encode_hello(self.endpoint.take_sequence(), time.monotonic(),
                                        self.side.joint_count, self.side.control_step),
                           address)

    def _send_state(self, address: Address) -> None:
        state = self.side.state(self.answered, self.status() | self._pending)
        self._pending = StatusFlag.NONE
        self.endpoint.send(encode_state(self.endpoint.take_sequence(), time.monotonic(), state),
                           address)

    def _record(self) -> None:
        if self._recording is not None and self.steps % self.record_every == 0:
            row = np.append(self.side.recording_row(), float(self.status() | self._pending))
            self._recording.append(row)

    def _advance(self) -> None:
        try:
            self.side.step()
        except SimulationDivergedError as error:
            # The side undid the step and engaged the safe state: flag it in the STATE
            # that answers and in the recording, count it, and end the run.
            self.divergences += 1
            self.divergence = str(error)
            self._stopping = True
            if self._recording is not None:
                row = np.append(self.side.recording_row(), float(self.status() | self._pending))
                self._recording.append(row)
            return
        self.steps += 1
        self._record()

    # --- message handling ----------------------------------------------------------------
    def _handle(self, message: Message, address: Address) -> None:
        kind = message.type
        if kind == MessageType.PING:
            now = time.monotonic()
            self.endpoint.send(encode_pong(self.endpoint.take_sequence(), message, now,
                                           time.monotonic()), address)
        elif kind == MessageType.HELLO:
            self.client = address
            self._pending |= StatusFlag.RESYNCHRONISED
            self._send_hello(address)
            self._send_state(address)
        elif kind == MessageType.BYE:
            self._stopping = True
        elif kind in _COMMAND_TYPE.values():
            if kind != self.command_type:
                self.wrong_commands += 1
                return
            self.client = address
            self._command(message, address)

    def _command(self, message: Message, address: Address) -> None:
        self.answered = message.sequence
        self._last_command = time.perf_counter()
        if self.mode == "realtime":
            if self._timed_out:
                self._timed_out = False
                self._pending |= StatusFlag.RESYNCHRONISED
            self.side.apply(message.values)
            return
        if message.sender_time < self.side.time - 0.5 * self.side.control_step:
            self.retransmissions += 1
        else:
            self.side.apply(message.values)
            self._advance()
        self._send_state(address)

    def _drain(self, timeout: float) -> None:
        for message, address in self.endpoint.receive(timeout):
            self._handle(message, address)
        refused = self.endpoint.refused_hellos
        while refused:
            address, _reason = refused.popleft()
            self.refused_hellos += 1
            self._send_hello(address)

    # --- loops ---------------------------------------------------------------------------
    def run(self, stop_request: StopFlag | None = None) -> dict[str, Any]:
        """Serve until ``BYE``, :meth:`stop`, ``stop_request`` or ``duration``.

        Returns
        -------
        dict
            Counters and figures (also written to ``timing.json`` with a run folder).
        """
        start = time.perf_counter()
        end = np.inf if self.duration is None else start + self.duration
        if self.folder is not None:
            columns = (*self.side.recording_columns(), "network status [-]")
            self._recording = NetworkRecording(self.folder, columns)
            self._record()
        try:
            if self.mode == "lockstep":
                while not self._stopped(stop_request) and time.perf_counter() < end:
                    self._drain(_IDLE_WAIT)
            else:
                self._realtime(stop_request, end)
        finally:
            self._finish(time.perf_counter() - start)
        return self.summary

    def _stopped(self, stop_request: StopFlag | None) -> bool:
        return self._stopping or (stop_request is not None and stop_request.requested)

    def _realtime(self, stop_request: StopFlag | None, end: float) -> None:
        period = self.side.control_step
        self.side.engage_safe_state()  # no command yet
        self._last_command = time.perf_counter()
        next_wake = time.perf_counter() + period
        spin = min(2e-4, 0.2 * period)
        while not self._stopped(stop_request):
            now = time.perf_counter()
            if now >= end:
                break
            remaining = next_wake - now
            if remaining > spin:
                self._drain(remaining - spin)
                continue
            if remaining > 0.0:
                continue  # spin the last fraction of the period for a precise wake-up
            self.wakeups.append(now)
            self._drain(0.0)
            if not self._timed_out and now - self._last_command > self.timeout \
                    and self.answered >= 0:
                self._engage_timeout()
            self._advance()
            if self.client is not None:
                self._send_state(self.client)
            next_wake += period
            if time.perf_counter() - next_wake > _CATCH_UP_PERIODS * period:
                next_wake = time.perf_counter() + period

    def _engage_timeout(self) -> None:
        self._timed_out = True
        self.timeouts += 1
        self.side.engage_safe_state()
        if self.client is not None:
            self.endpoint.tracker(self.client).reset()

    def _finish(self, wall_time: float) -> None:
        self.summary = {
            "mode": self.mode, "command kind": self.side.command_kind,
            "control steps [count]": self.steps, "simulated time [s]": self.side.time,
            "wall time [s]": wall_time, "retransmissions [count]": self.retransmissions,
            "wrong command kind [count]": self.wrong_commands,
            "timeouts [count]": self.timeouts,
            "refused hellos [count]": self.refused_hellos,
            "clamped commands [count]": self.side.clamped_commands,
            "divergences [count]": self.divergences,
        } | self.endpoint.counters()
        if self.divergence is not None:
            self.summary["error"] = self.divergence
        if self.wakeups:
            self.summary |= jitter_statistics(np.array(self.wakeups), self.side.control_step)
        self.endpoint.close()
        if self.folder is not None and self._recording is not None:
            self._recording.close()
            self.summary = write_network_files(self.folder, self.endpoint.log,
                                               self.side.control_step, self.summary,
                                               self.plots)
            write_run_description(self.folder, self.side.robot, self.summary)
