"""The actuator client: an :class:`ActuatorSide` driving a remote dynamics server in lockstep.

The session starts with ``HELLO``: the server answers with its own ``HELLO`` (joint count
and control step, read into :attr:`ActuatorClient.server_joint_count` and
:attr:`ActuatorClient.server_control_step`) and its current ``STATE``; dimensions other
than this side's end the session with :class:`SessionMismatchError`.

The loop is the thesis's split seen from the Simulink side (Daepp 2011, ch. 5.1): send
the cylinder forces (``FORCE_COMMAND``, sender time = the simulation time at which they
take effect), wait for the ``STATE`` that answers them, compute the next forces. When no
answer arrives within ``reply_timeout`` the same forces are sent again under a new
sequence number (counted); the server recognises the retransmission by its sender time
and does not step twice, so lost datagrams delay the run but do not change it.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from pneumaquad.network.actuator_side import ActuatorSide
from pneumaquad.network.endpoint import DEFAULT_HOST, Address, UdpEndpoint
from pneumaquad.network.experiments import Experiment
from pneumaquad.network.protocol import (
    STEP_TOLERANCE,
    ProtocolError,
    encode_bye,
    encode_command,
    encode_hello,
    hello_parameters,
)
from pneumaquad.network.run_output import (
    NetworkRecording,
    write_network_files,
    write_run_description,
)
from pneumaquad.network.server import StopFlag
from pneumaquad.network.state import StateMessage, StatusFlag, state_from_values
from pneumaquad.network.wire import Message, MessageType

__all__ = ["ActuatorClient", "DynamicsDivergedError", "NoReplyError", "SessionMismatchError"]


class NoReplyError(ConnectionError):
    """The dynamics server did not answer within the retry budget."""


class DynamicsDivergedError(RuntimeError):
    """The dynamics server flagged ``DIVERGED``: its simulation diverged and the run ends."""


class SessionMismatchError(ConnectionError):
    """The dynamics server announced a joint count or control step other than this side's."""


class ActuatorClient:
    """Run an :class:`ActuatorSide` against a dynamics server (force commands, lockstep).

    Parameters
    ----------
    side
        The actuator side.
    dynamics
        Server ``(host, port)``.
    bind
        Local ``(host, port)``; 127.0.0.1 and a free port by default.
    reply_timeout
        Wait for a ``STATE`` before resending [s].
    max_retries
        Resends of one command before :class:`NoReplyError`.
    folder
        Run folder (recording of angles, forces and valve commands, packet files).
    """

    def __init__(self, side: ActuatorSide, dynamics: Address,
                 bind: Address = (DEFAULT_HOST, 0), reply_timeout: float = 0.05,
                 max_retries: int = 100, folder: Path | None = None,
                 busy_wait: float = 0.0) -> None:
        self.side = side
        self.dynamics = dynamics
        self.endpoint = UdpEndpoint(bind, dynamics, side.joint_count, busy_wait=busy_wait)
        self.reply_timeout = reply_timeout
        self.max_retries = max_retries
        self.folder = None if folder is None else Path(folder)
        self.resends = 0  # commands sent again after a reply timeout [count]
        self.steps = 0
        #: Joint count and control step [s] the server announced in its HELLO.
        self.server_joint_count: int | None = None
        self.server_control_step: float | None = None
        self.states: list[StateMessage] = []
        self.summary: dict[str, Any] = {}

    def _exchange(self, datagram_for: Any, accept: Any) -> StateMessage:
        """Send ``datagram_for(sequence)`` until a ``STATE`` satisfying ``accept`` arrives."""
        sent: set[int] = set()
        for attempt in range(self.max_retries + 1):
            if attempt:
                self.resends += 1
            sequence = self.endpoint.take_sequence()
            sent.add(sequence)
            self.endpoint.send(datagram_for(sequence), self.dynamics)
            deadline = time.perf_counter() + self.reply_timeout
            while (remaining := deadline - time.perf_counter()) > 0:
                for message, _ in self.endpoint.receive(remaining):
                    if message.type == MessageType.HELLO:
                        self._read_server_hello(message)
                    if message.type != MessageType.STATE:
                        continue
                    state = state_from_values(np.asarray(message.values), self.side.joint_count)
                    if accept(state, sent):
                        return state
        raise NoReplyError(f"no STATE from {self.dynamics} after {self.max_retries} resends")

    def _read_server_hello(self, hello: Message) -> None:
        """Take the server's dimensions from its ``HELLO``; refuse other ones than ours."""
        try:
            joints, step = hello_parameters(hello)
        except ProtocolError:
            return  # the endpoint drops invalid HELLOs already
        self.server_joint_count, self.server_control_step = joints, step
        same_step = abs(step - self.side.control_step) <= STEP_TOLERANCE * step
        if joints != self.side.joint_count or not same_step:
            raise SessionMismatchError(
                f"the dynamics server at {self.dynamics[0]}:{self.dynamics[1]} simulates "
                f"{joints} joints with a {step:g} s control step; this actuator side has "
                f"{self.side.joint_count} joints and a {self.side.control_step:g} s step "
                "(use the same --params, --set and --configuration on both sides)")

    def connect(self) -> StateMessage:
        """``HELLO``, the server's ``HELLO`` and its first ``STATE``; resets the actuators to
        the state's posture and pistons.

        Raises
        ------
        SessionMismatchError
            The server announced another joint count or control step.
        NoReplyError
            No ``HELLO`` and ``STATE`` came back within the retry budget.
        """
        self.endpoint.sequence = 0
        self.server_joint_count = self.server_control_step = None
        state = self._exchange(
            lambda sequence: encode_hello(sequence, time.monotonic(), self.side.joint_count,
                                          self.side.control_step),
            lambda state, sent: self.server_joint_count is not None)
        self.side.set_pose(state.joint_angles, piston_positions=state.piston_positions)
        return state

    def run(self, experiment: Experiment | None, steps: int,
            initial: StateMessage | None = None,
            stop_request: StopFlag | None = None) -> dict[str, Any]:
        """Run ``steps`` control steps (after :meth:`connect`, whose state is ``initial``).

        Parameters
        ----------
        experiment
            References of every step (all joints closed loop); ``None``: the caller set
            the commands of :attr:`side`.
        steps
            Control steps.
        initial
            State to start from; :meth:`connect` is called when omitted.
        stop_request
            Checked every step: ``requested`` ends the run early (Ctrl-C).

        Returns
        -------
        dict
            Counters and round-trip figures (also ``timing.json`` with a run folder).
        """
        state = self.connect() if initial is None else initial
        recording = None
        if self.folder is not None:
            names = self.side.robot.joint_names
            columns = ["time [s]"] + [f"{j} {q}" for j in names for q in (
                "reference [rad]", "angle [rad]", "force [N]", "command [V]",
                "cap pressure [Pa]", "rod pressure [Pa]")]
            recording = NetworkRecording(self.folder, columns)
        start = time.perf_counter()
        try:
            for _ in range(steps):
                if stop_request is not None and stop_request.requested:
                    break
                if experiment is not None:
                    self.side.command_angles(experiment.references(self.steps))
                forces = self.side.forces(state)
                state = self.exchange_forces(forces, state.simulation_time)
                if state.status & StatusFlag.DIVERGED:
                    raise DynamicsDivergedError(
                        f"the dynamics server reports that the simulation diverged at "
                        f"t = {state.simulation_time:.4g} s (it ends the run)")
                self.steps += 1
                self.states.append(state)
                if recording is not None:
                    pressures = self.side.chamber_pressures()
                    recording.append(np.concatenate([[state.simulation_time], np.column_stack(
                        [self.side.reference_angles, state.joint_angles, forces,
                         self.side.valve_commands(), pressures[:, 0], pressures[:, 1]]
                    ).ravel()]))
        finally:
            self._finish(time.perf_counter() - start, recording)
        return self.summary

    def exchange_forces(self, forces: np.ndarray, effect_time: float) -> StateMessage:
        """Send ``forces`` [N] for ``effect_time`` [s], return the answering ``STATE``."""
        return self._exchange(
            lambda sequence: encode_command(MessageType.FORCE_COMMAND, sequence, effect_time,
                                            forces, self.side.joint_count),
            lambda reply, sent: reply.answered_sequence in sent)

    def bye(self) -> None:
        """Tell the server the session ends (sent three times: it is not acknowledged)."""
        for _ in range(3):
            self.endpoint.send(encode_bye(self.endpoint.take_sequence(), time.monotonic()),
                               self.dynamics)

    def _finish(self, wall_time: float, recording: NetworkRecording | None) -> None:
        from pneumaquad.network.timing import round_trip_times, rtt_statistics

        self.summary = {"control steps [count]": self.steps, "wall time [s]": wall_time,
                        "resends [count]": self.resends} | self.endpoint.counters()
        self.summary |= rtt_statistics(round_trip_times(self.endpoint.log, "command"))
        if recording is not None and self.folder is not None:
            recording.close()
            self.summary = write_network_files(self.folder, self.endpoint.log,
                                               self.side.control_step, self.summary)
            write_run_description(self.folder, self.side.robot, self.summary)

    def close(self) -> None:
        """Close the socket."""
        self.endpoint.close()
