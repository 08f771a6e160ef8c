"""A networked run folder is a run folder: `pneumaquad report` adds its packet timing."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np

from conftest import interrupt_when_recording
from pneumaquad.network.actuator_side import ActuatorSide
from pneumaquad.network.client import ActuatorClient
from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.experiments import make_experiment
from pneumaquad.network.server import DynamicsServer
from pneumaquad.params import load_robot
from pneumaquad.reporting import build_run_report
from pneumaquad.robot.builder import build_robot

POSE = np.tile(np.radians([0.0, -30.0, 60.0]), 4)


def _robot():
    return build_robot(load_robot("crr-quadruped"), "fixed")


def test_reports_of_both_sides_of_a_networked_run(tmp_path: Path) -> None:
    dynamics = DynamicsSide(_robot(), "force")
    dynamics.set_pose(POSE)
    server = DynamicsServer(dynamics, duration=30.0, folder=tmp_path / "dynamics")
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    client = ActuatorClient(ActuatorSide(_robot()), server.address, folder=tmp_path / "act")
    try:
        initial = client.connect()
        experiment = make_experiment("gamma-step", client.side.robot.joint_names,
                                     initial.joint_angles, client.side.control_step, 0.05)
        client.run(experiment, 200, initial)
        client.bye()
    finally:
        client.close()
        server.stop()
        thread.join(10.0)
    for side in ("dynamics", "act"):
        for name in ("parameters.toml", "model.xml", "summary.json", "timing.json"):
            assert (tmp_path / side / name).is_file(), (side, name)
        page = build_run_report(tmp_path / side).read_text(encoding="utf-8")
        assert "Network timing" in page
        assert page.count("data:image/png;base64") >= 3
    act_page = (tmp_path / "act" / "report" / "report.html").read_text(encoding="utf-8")
    assert "front right: reference and simulated angle" in act_page  # commanded leg plot


def test_ctrl_c_stops_the_dynamics_server_with_its_files(tmp_path: Path) -> None:
    """A real SIGINT to `pneumaquad serve dynamics` in real time: exit status 130, the
    recording and the packet files written and readable."""
    import json
    import socket

    from pneumaquad.io.run_folder import read_recording
    from pneumaquad.network.protocol import MessageType, encode_command

    out = tmp_path / "served"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sequence = 0

    def send_command() -> None:  # valve commands until rows are being written
        nonlocal sequence
        sequence += 1
        client.sendto(encode_command(MessageType.VALVE_COMMAND, sequence, 0.0,
                                     np.full(12, 5.25)), ("127.0.0.1", port))

    try:  # a cold numba cache takes a while to start
        returncode, stderr = interrupt_when_recording(
            ["serve", "dynamics", "--command", "valve", "--mode", "realtime", "--port",
             str(port), "--record-every", "10", "-o", str(out)],
            out / "recording.csv", 20_000, 120.0, between_polls=send_command,
            poll_interval=0.002,
        )
    finally:
        client.close()
    assert returncode == 130, stderr
    recording = read_recording(out / "recording.parquet")
    assert recording["time [s]"].size > 10
    assert json.loads((out / "timing.json").read_text())["received [count]"] > 10
