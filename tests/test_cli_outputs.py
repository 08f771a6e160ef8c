"""Where the commands write and how they stop: ``robot export`` under runs/ unless told
otherwise, ``video`` ending on Ctrl-C with a message and status 130, an interrupted robot
run printing its figures once."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import mujoco
import pytest
from typer.testing import CliRunner

from conftest import CLI
from pneumaquad.cli import robot as cli_robot
from pneumaquad.cli.main import app

runner = CliRunner()


def test_robot_export_writes_under_runs_unless_given_a_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["robot", "export", "--environment", "ramp"])
    assert result.exit_code == 0, result.output
    (written,) = (tmp_path / "runs").glob("robot-export-*/model.xml")
    assert str(written.relative_to(tmp_path)) in " ".join(result.output.split())
    model = mujoco.MjModel.from_xml_path(str(written))
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ramp") >= 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runs"]  # nothing in the tree

    chosen = tmp_path / "mine.xml"
    assert runner.invoke(app, ["robot", "export", str(chosen)]).exit_code == 0
    first = chosen.read_text()
    refused = runner.invoke(app, ["robot", "export", str(chosen), "--environment", "ramp"])
    assert refused.exit_code == 2
    assert "--overwrite" in " ".join(refused.output.split())
    assert chosen.read_text() == first
    replaced = runner.invoke(app, ["robot", "export", str(chosen), "--environment", "ramp",
                                   "--overwrite"])
    assert replaced.exit_code == 0, replaced.output
    assert chosen.read_text() != first


class _InterruptedWorker:
    """A video worker whose wait is cut by Ctrl-C (as a real worker's wait raises a second
    one, the first having stopped it)."""

    cancelled = False

    def __init__(self, settings: object) -> None:
        self.settings = settings

    def __enter__(self) -> _InterruptedWorker:
        return self

    def __exit__(self, *exception: object) -> None:
        _InterruptedWorker.cancelled = True  # the real worker removes its partial files

    def finish(self, run_folder: Path) -> None:
        self.folder = run_folder

    def wait(self, progress=None):
        raise KeyboardInterrupt


def test_ctrl_c_while_rendering_a_video_ends_with_130_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cli_robot, "VideoWorker", _InterruptedWorker)
    result = runner.invoke(app, ["video", str(tmp_path)])
    assert result.exit_code == 130
    assert "no video: interrupted again (Ctrl-C)" in " ".join(result.output.split())
    assert "Traceback" not in result.output
    assert _InterruptedWorker.cancelled


def test_an_interrupted_robot_run_prints_its_figures_once(tmp_path: Path) -> None:
    out = tmp_path / "long"
    csv = out / "recording.csv"
    process = subprocess.Popen([*CLI, "robot", "stand", "--hold", "3000", "-o", str(out)],
                               cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    try:
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline and not (csv.is_file()
                                                   and csv.stat().st_size > 200_000):
            time.sleep(0.1)
        process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 130, stderr
    assert stdout.count("run folder:") == 1 and stdout.count("simulated time [s]") == 1
    assert "interrupted: the recording holds the part that ran" in stderr
