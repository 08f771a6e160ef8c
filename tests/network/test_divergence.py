"""A diverging dynamics never resets silently: the step is undone, the safe state engaged,
the STATE and the recording flagged DIVERGED, the divergence counted and the run ended."""

from __future__ import annotations

import socket
import struct
import threading
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.server import DynamicsServer
from pneumaquad.network.state import StatusFlag, state_from_values
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.errors import SimulationDivergedError

# 30 ms steps, explicit Euler and massless pistons: full-force commands that flip sign
# every step blow the legs up within a few steps
UNSTABLE = ('simulation.control_step="30 ms"', 'simulation.integrator="euler"',
            *(f'linkages.{joint}.moving_mass="0 kg"' for joint in ("alpha", "beta", "gamma")))
POSE = np.tile(np.radians((0.0, -30.0, 60.0)), 4)
HEADER = struct.Struct("<4sHHIdHH")  # docs/protocol.md
FORCE_COMMAND, STATE = 2, 4


def _side() -> DynamicsSide:
    side = DynamicsSide(build_robot(load_robot("crr-quadruped", list(UNSTABLE)), "fixed"),
                        "force")
    side.set_pose(POSE)
    return side


def _alternating(step: int) -> np.ndarray:
    return np.full(12, 160.0 if step % 2 == 0 else -130.0)  # inside the force limits


def test_a_diverging_step_is_undone_and_flagged() -> None:
    side = _side()
    times = []
    with pytest.raises(SimulationDivergedError, match="diverged at t ="):
        for step in range(200):
            side.apply(_alternating(step))
            side.step()
            times.append(side.time)
    assert side.diverged and side.safe
    assert side.simulation.divergences == 1
    assert side.time == pytest.approx(times[-1])  # the last good state, no jump back
    state = side.state()
    assert np.all(np.isfinite(state.joint_angles))  # encodable: the good state is held
    assert side.state(status=StatusFlag.DIVERGED).status & StatusFlag.DIVERGED
    side.set_pose(POSE)
    assert not side.diverged


def _datagram(sequence: int, sender_time: float, values: np.ndarray) -> bytes:
    return HEADER.pack(b"PNQD", 1, FORCE_COMMAND, sequence, sender_time, len(values), 0) + \
        struct.pack(f"<{len(values)}d", *values)



def test_lockstep_server_flags_counts_and_ends_on_divergence(
        tmp_path: Path, client_socket: socket.socket) -> None:
    side = _side()
    server = DynamicsServer(side, ("127.0.0.1", 0), mode="lockstep", duration=30.0,
                            folder=tmp_path)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    statuses, times = [], []
    simulated = 0.0
    for step in range(200):
        client_socket.sendto(_datagram(step, simulated, _alternating(step)), server.address)
        data = client_socket.recv(4096)
        _, _, kind, _, _, count, _ = HEADER.unpack_from(data)
        assert kind == STATE
        state = state_from_values(
            np.array(struct.unpack_from(f"<{count}d", data, HEADER.size)), 12)
        statuses.append(state.status)
        times.append(state.simulation_time)
        simulated = state.simulation_time
        if state.status & StatusFlag.DIVERGED:
            break
    thread.join(timeout=10.0)
    assert not thread.is_alive()  # the run ended by itself
    assert statuses[-1] & StatusFlag.DIVERGED and statuses[-1] & StatusFlag.SAFE_STATE
    assert not any(status & StatusFlag.DIVERGED for status in statuses[:-1])
    assert np.all(np.diff(times) >= 0.0)  # simulated time never went back
    assert server.summary["divergences [count]"] == 1
    assert "diverged" in server.summary["error"]
    recording = pq.read_table(tmp_path / "recording.parquet").to_pydict()
    flags = np.array(recording["network status [-]"], dtype=int)
    assert flags[-1] & StatusFlag.DIVERGED and not np.any(flags[:-1] & StatusFlag.DIVERGED)


def test_thesis_layout_server_ends_on_divergence() -> None:
    """The thesis's 21-double layout has no status field: the server answers with the last
    good state, counts the divergence and ends the run."""
    from pneumaquad.network.thesis import encode_thesis_command
    from pneumaquad.network.thesis_server import ThesisServer

    robot = build_robot(load_robot("crr-quadruped", list(UNSTABLE)), "fixed")
    side = DynamicsSide(robot, "torque")
    side.set_pose(POSE)
    server = ThesisServer(side, ("127.0.0.1", 0))
    try:
        times = []
        for step in range(400):
            torque = 8.0 if step % 2 == 0 else -8.0
            reply = server.handle(encode_thesis_command([torque, -torque, torque]))
            assert reply is not None
            times.append(side.time)
            if server.divergences:
                break
        assert server.divergences == 1 and "diverged" in server.divergence
        assert side.diverged and np.all(np.diff(times) >= 0.0)
        assert server.steps == len(times) - 1  # the diverging step was not counted
    finally:
        server.socket.close()
