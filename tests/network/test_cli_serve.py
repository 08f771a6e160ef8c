"""``serve`` commands: user errors exit 2; the actuator client runs against a server."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from pneumaquad.cli.serve import serve_app
from pneumaquad.network.dynamics_side import DynamicsSide
from pneumaquad.network.server import DynamicsServer
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot

runner = CliRunner()


def test_user_errors_exit_2() -> None:
    for arguments in (["dynamics", "--command", "pressure"],
                      ["dynamics", "--mode", "sometimes"],
                      ["dynamics", "--peer", "localhost:notaport"],
                      ["dynamics", "--configuration", "hexapod"],
                      ["actuators", "--dynamics", "127.0.0.1:99999"],
                      ["actuators", "--experiment", "dance"]):
        result = runner.invoke(serve_app, arguments)
        assert result.exit_code == 2, (arguments, result.output)


def test_actuators_command_runs_against_a_dynamics_server(tmp_path: Path) -> None:
    side = DynamicsSide(build_robot(load_robot("crr-quadruped"), "fixed"), "force")
    side.set_pose(np.tile(np.radians((0.0, -30.0, 60.0)), 4))
    server = DynamicsServer(side, duration=30.0)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    host, port = server.address
    result = runner.invoke(serve_app, ["actuators", "--dynamics", f"{host}:{port}",
                                       "--duration", "0.05", "--settle", "0.01",
                                       "--output", str(tmp_path)])
    thread.join(5.0)
    assert result.exit_code == 0, result.output
    assert not thread.is_alive() and server.steps == 50  # stopped by the client's BYE
    for name in ("recording.parquet", "packets.parquet", "timing.json", "rtt.png"):
        assert (tmp_path / name).is_file(), name
    # the missed deadlines are said, not only filed in timing.json
    timing = json.loads((tmp_path / "timing.json").read_text())
    late, total = timing["round trips over deadline [count]"], timing["round trips [count]"]
    assert f"round trips over the 1 ms deadline: {late} of {total}" in result.output
