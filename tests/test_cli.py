"""Command line: runs write their folders, bad input exits 2 with a message, Ctrl-C keeps data."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

from conftest import CLI, interrupt_when_recording
from pneumaquad.io.run_folder import read_recording
from pneumaquad.params import load_rig
from pneumaquad.reporting.rig_experiment import run_rig_experiment
from pneumaquad.rig import signals


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_step_run_writes_folder(tmp_path: Path) -> None:
    out = tmp_path / "step"
    done = run_cli(
        "rig",
        "step",
        "6 V",
        "--duration",
        "2 s",
        "--step-time",
        "0.5 s",
        "-o",
        str(out),
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    for name in (
        "parameters.toml",
        "recording.csv",
        "recording.parquet",
        "summary.json",
        "rig.png",
    ):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 2000
    assert summary["interrupted"] is False
    recording = read_recording(out / "recording.csv")
    # normal litres at DIN 1343 (0 °C, 1.01325 bar): rho_n = 101325 / (287 · 273.15)
    normal_density = 101325.0 / (287.0 * 273.15)
    assert np.allclose(
        recording["air consumed [NL]"], recording["air consumed [kg]"] / normal_density * 1e3
    )
    assert recording["air consumed [kg]"][-1] > 0.0
    assert np.allclose(
        recording["net force [N]"],
        recording["pneumatic force [N]"] - recording["friction force [N]"],
    )
    # The piston ends extended against the stop: a 6 V command extends (cap port 2).
    assert summary["final position [m]"] == pytest.approx(1.75 * 0.0254, abs=1e-3)
    # The resolved parameters load back and reproduce the run's set.
    assert load_rig(out / "parameters.toml") == load_rig("thesis-rig")


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("rig", "step", "6 kg"), "VOLTAGE: '6 kg' is a mass"),
        (("rig", "step", "12 V"), "VOLTAGE"),
        (
            ("rig", "step", "6 V", "--set", 'supply.supply_pressure="50 kg"'),
            "supply.supply_pressure: '50 kg'",
        ),
        (("rig", "step", "6 V", "--set", 'cylinder.bore="-1 in"'), "cylinder.bore"),
        (("rig", "step", "6 V", "--set", "cylinder.colour=1"), "cylinder.colour"),
        (("rig", "step", "6 V", "--params", "no-such-set"), "no-such-set"),
        (("rig", "track", "sine", "--amplitude", "3 psi"), "--amplitude"),
        (("rig", "track", "wobble"), "REFERENCE"),
        (("rig", "track", "file", "--file", "missing.csv"), "missing.csv"),
        (
            ("rig", "step", "6 V", "--set", 'cylinder.bore="1e300 in"'),
            "cylinder.bore: '1e300 in' should be greater than 0 m and at most 10 m",
        ),
        (
            ("rig", "step", "6 V", "--set", "gas.heat_capacity_ratio=1e300"),
            "gas.heat_capacity_ratio: 1e+300 should be greater than 1 and at most 5/3",
        ),
        (
            ("rig", "step", "6 V", "--set", 'rig.gravity="1e300 m/s^2"'),
            "rig.gravity: '1e300 m/s^2' should be at least 0 m/s^2 and at most 100 m/s^2",
        ),
        (
            ("rig", "step", "6 V", "--duration", "-1 s"),
            "--duration: '-1 s' should be greater than 0 s and at most 3600 s",
        ),
        (
            ("rig", "step", "6 V", "--duration", "1e300 s"),
            "--duration: '1e300 s' should be greater than 0 s and at most 3600 s",
        ),
        (
            (
                "rig",
                "step",
                "6 V",
                "--set",
                'simulation.integrator="radau"',
                "--set",
                'friction.model="coulomb"',
            ),
            "set-valued friction.model",
        ),
    ],
)
def test_bad_input_exits_2_without_traceback(tmp_path: Path, args, fragment: str) -> None:
    done = run_cli(*args, cwd=tmp_path)
    assert done.returncode == 2
    assert fragment in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "runs").exists() or not any((tmp_path / "runs").iterdir())


@pytest.mark.parametrize(
    "shape_args",
    [
        ("sine", "--duration", "2 s"),
        ("chirp", "--duration", "2 s", "--frequency", "0.5 Hz", "--end-frequency", "2 Hz"),
        ("step", "--levels", "0.5 in,1.2 in", "--dwell", "1 s"),
        ("trapezoid", "--levels", "0.5 in,1.2 in", "--ramp", "0.3 s", "--dwell", "0.2 s"),
    ],
)
def test_every_reference_shape_tracks(tmp_path: Path, shape_args: tuple[str, ...]) -> None:
    out = tmp_path / "run"
    done = run_cli("rig", "track", *shape_args, "-o", str(out), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    # a closed loop that works: the piston follows within a fraction of the stroke
    assert summary["rmse [% stroke]"] < 15.0
    assert summary["steps"] == 2000


def test_interrupted_run_keeps_recording(tmp_path: Path) -> None:
    """Ctrl-C between chunks: the part that ran is recorded, flushed and readable."""
    setup = load_rig("thesis-rig")
    signal = signals.sine(0.02, 0.005, 0.5, 5.0, setup.simulation.control_step)
    calls = []

    def interrupt_after_two_chunks(done: int, total: int) -> None:
        calls.append(done)
        if len(calls) == 2:
            raise KeyboardInterrupt

    result, summary = run_rig_experiment(
        setup, tmp_path, signal, True, "interrupted", progress=interrupt_after_two_chunks
    )
    assert result.interrupted and summary["interrupted"]
    recording = read_recording(tmp_path / "recording.csv")
    assert recording["time [s]"].size == calls[-1] == summary["steps"]
    assert np.all(np.isfinite(recording["position [m]"]))
    assert (tmp_path / "recording.parquet").is_file()
    assert (tmp_path / "rig.png").is_file()


@pytest.mark.parametrize("suffix", [".csv", ".mat"])
def test_recorded_reference_file(tmp_path: Path, suffix: str) -> None:
    times = np.linspace(0.0, 2.0, 201)
    millimetres = 22.0 + 5.0 * np.sin(2 * np.pi * times)
    path = tmp_path / f"lab{suffix}"
    if suffix == ".csv":
        np.savetxt(
            path, np.column_stack([times, millimetres]), delimiter=",", header="t,x", comments=""
        )
    else:
        savemat(path, {"t": times, "x": millimetres})
    reference = signals.recorded_reference(path, "t", "x", 1e-3, 1e-3)
    assert reference.size == 2000
    grid = np.arange(2000) * 1e-3
    expected = 0.022 + 0.005 * np.sin(2 * np.pi * grid)
    assert np.max(np.abs(reference - expected)) < 2e-5  # linear interpolation of 10 ms data
    out = tmp_path / "run"
    done = run_cli(
        "rig",
        "track",
        "file",
        "--file",
        str(path),
        "--time-column",
        "t",
        "--position-column",
        "x",
        "--position-unit",
        "mm",
        "-o",
        str(out),
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 2000


def test_recorded_reference_in_milliseconds(tmp_path: Path) -> None:
    """A lab file's time column in ms (the demo's lab CSV): --time-unit ms reads it as the
    same reference as seconds."""
    times = np.arange(0.0, 2.0, 0.01)
    seconds, millis = tmp_path / "s.csv", tmp_path / "ms.csv"
    for path, scale in ((seconds, 1.0), (millis, 1e3)):
        np.savetxt(path, np.column_stack([times * scale, 0.02 + 0.004 * times]), delimiter=",",
                   header="t,x", comments="")
    expected = signals.recorded_reference(seconds, "t", "x", 1.0, 1e-3)
    np.testing.assert_allclose(
        signals.recorded_reference(millis, "t", "x", 1.0, 1e-3, time_scale=1e-3), expected,
        rtol=0, atol=1e-15)
    out = tmp_path / "run"
    done = run_cli("rig", "track", "file", "--file", str(millis), "--time-column", "t",
                   "--time-unit", "ms", "--position-column", "x", "-o", str(out), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads((out / "summary.json").read_text())["steps"] == expected.size


def test_recorded_reference_rejects_non_monotonic_time(tmp_path: Path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("t,x\n0,1\n0.2,2\n0.1,3\n")
    with pytest.raises(signals.RecordedReferenceError, match="not increasing"):
        signals.recorded_reference(path, "t", "x", 1.0, 1e-3)


def test_ctrl_c_on_the_command_line_keeps_the_recording(tmp_path: Path) -> None:
    """A real SIGINT to a running `rig track`: exit status 130, readable files, summary
    marked interrupted."""
    out = tmp_path / "long"
    csv = out / "recording.csv"
    returncode, stderr = interrupt_when_recording(  # wait at most 60 s for rows
        ["rig", "track", "sine", "--duration", "3000 s", "-o", str(out)], csv, 10_000, 60.0,
        cwd=tmp_path,
    )
    assert returncode == 130, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True
    recording = read_recording(out / "recording.parquet")
    assert 0 < recording["time [s]"].size == summary["steps"] < 3_000_000
    assert np.all(np.isfinite(recording["cap pressure [Pa]"]))
    assert read_recording(out / "recording.csv")["time [s]"].size == summary["steps"]


def test_params_check_refuses_a_file_that_is_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes(b'[meta]\nname = "B\xe9zier"\n')
    done = run_cli("params", "check", str(path), cwd=tmp_path)
    assert done.returncode == 2
    assert "is not UTF-8 text (byte 0xe9 at offset 16)" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("rig", "step", "11 V"), "VOLTAGE: '11 V' should be at least 0 V and at most 10 V"),
        (("rig", "track", "sine", "--duration", "1e300 s"), "--duration: '1e300 s'"),
        (("rig", "track", "chirp", "--duration", "0 s"), "--duration: '0 s'"),
        (("rig", "track", "sine", "--frequency", "1 kHz"), "at most 500 Hz"),
        (("rig", "track", "sine", "--amplitude", "3 in"), "at most cylinder.stroke"),
        (("rig", "track", "step", "--dwell", "1000 s"), "at most 3600 s in all"),
        (("rig", "track", "trapezoid", "--cycles", "1000"), "at most 3600 s in all"),
        (("rig", "step", "6 V", "--step-time", "11 s"), "at most --duration (10 s)"),
        (
            ("rig", "step", "6 V", "--duration", "3600 s", "--set",
             'simulation.control_step="1 us"'),
            "needs 3.6e+09 control steps",
        ),
    ],
)
def test_rig_options_are_checked_before_anything_runs(tmp_path: Path, args, fragment: str,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from typer.testing import CliRunner

    from pneumaquad.cli.main import app
    from pneumaquad.params import ParameterError

    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, list(args))
    assert isinstance(result.exception, ParameterError), result.output
    assert fragment in str(result.exception)
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("robot", "stand", "--hold", "inf"), "inf should be at least 0 s and at most 3600 s"),
        (("leg", "validate", "--settle", "nan"), "nan should be at least 0 s"),
        (("leg", "foot-cycle", "--cycles", "100000"), "at most 1000"),
        (("robot", "walk", "--distance", "100", "--speed", "0.001"), "takes 1e+05 s"),
        (("rig", "track", "trapezoid", "--cycles", "0"), "at least 1 and at most 10000"),
        (("serve", "dynamics", "--duration", "-1"), "should be greater than 0 s"),
        (("serve", "dynamics", "--port", "70000"), "at most 65535"),
        (("serve", "actuators", "--duration", "1e300"), "at most 3600 s"),
        (("report", "--cost-table", "--duration", "inf"), "at most 3600 s"),
        (("console", "--duration", "-5"), "greater than 0 s"),
        (("robot", "walk", "--waypoints", "0.5"), "waypoint '0.5': expected two numbers"),
        (("robot", "walk", "--waypoints", "0.5,0;0.5,0.001"), "at least 1 cm apart"),
    ],
)
def test_numeric_options_are_finite_and_bounded(tmp_path: Path, args, fragment: str,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    from typer.testing import CliRunner

    from pneumaquad.cli.main import app

    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, list(args))
    assert result.exit_code == 2, result.output
    assert fragment in " ".join(result.output.replace("│", " ").split()), result.output
    assert not (tmp_path / "runs").exists()


def test_profile_writes_where_the_wall_time_went(tmp_path: Path) -> None:
    out = tmp_path / "profiled"
    done = run_cli("rig", "track", "sine", "--duration", "0.5 s", "--profile", "--output",
                   str(out), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "command real-time factor" in done.stdout  # results: standard output
    assert "command real-time factor" not in done.stderr
    profile = json.loads((out / "profile.json").read_text())
    stages = profile["stages"]
    for stage in ("start-up", "simulation", "recording", "plot"):
        assert stages[stage]["seconds"] > 0.0
    timed = sum(entry["seconds"] for name, entry in stages.items() if ":" not in name)
    assert timed + profile["untimed [s]"] == pytest.approx(profile["total [s]"])
    assert profile["simulated time [s]"] == pytest.approx(0.5)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["real-time factor"] == pytest.approx(0.5 / summary["wall time [s]"])


@pytest.mark.parametrize("name", ["thesis-rig", "crr-gamma", "crr-quadruped"])
def test_params_show_and_check_every_kind_of_set(tmp_path: Path, name: str) -> None:
    shown = run_cli("params", "show", name, cwd=tmp_path)
    assert shown.returncode == 0, shown.stderr
    resolved = tmp_path / f"{name}.toml"
    resolved.write_text(shown.stdout)
    checked = run_cli("params", "check", str(resolved), cwd=tmp_path)
    assert checked.returncode == 0, checked.stderr


def test_version_prints_the_installed_version(tmp_path: Path) -> None:
    from importlib.metadata import version

    done = run_cli("--version", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"pneumaquad {version('pneumaquad')}"


def test_default_run_folders_name_the_command(tmp_path: Path) -> None:
    step = run_cli("rig", "step", "6 V", "--duration", "0.2 s", "--step-time", "0.1 s",
                   cwd=tmp_path)
    tracked = run_cli("rig", "track", "step", "--levels", "0.5 in,0.6 in", "--dwell", "0.1 s",
                      cwd=tmp_path)
    assert step.returncode == 0 and tracked.returncode == 0, step.stderr + tracked.stderr
    names = sorted(folder.name for folder in (tmp_path / "runs").iterdir())
    assert len(names) == 2
    assert names[0].startswith("rig-step-") and names[1].startswith("rig-track-step-")


def test_an_output_folder_with_files_needs_overwrite(tmp_path):
    from typer.testing import CliRunner

    from pneumaquad.cli.main import app

    runner = CliRunner()
    step = ["rig", "step", "6 V", "--duration", "0.2 s", "--step-time", "0.1 s"]
    occupied = tmp_path / "old-run"
    occupied.mkdir()
    (occupied / "video.mp4").write_bytes(b"old")
    refused = runner.invoke(app, [*step, "-o", str(occupied)])
    assert refused.exit_code == 2
    assert "--overwrite" in " ".join(refused.output.split())
    assert sorted(path.name for path in occupied.iterdir()) == ["video.mp4"]  # untouched
    accepted = runner.invoke(app, [*step, "-o", str(occupied), "--overwrite"])
    assert accepted.exit_code == 0, accepted.output
    assert (occupied / "summary.json").is_file()
    empty = tmp_path / "empty"
    empty.mkdir()
    assert runner.invoke(app, [*step, "-o", str(empty)]).exit_code == 0


def test_the_command_line_loads_no_simulator_to_show_its_help():
    """``pneumaquad --help`` builds every command's options without importing MuJoCo, the
    robot's simulation, Matplotlib, scipy.signal (the controller fit) or the thesis
    validation (benchmarks/cli_startup.py times it)."""
    import sys

    code = ("import sys, pneumaquad.cli.main; "
            "print(sorted(m for m in ('mujoco', 'matplotlib', "
            "'pneumaquad.robot.simulation', 'pneumaquad.locomotion.walking', "
            "'scipy.signal', 'pneumaquad.validation.comparison', "
            "'pneumaquad.identification.controller') "
            "if m in sys.modules))")
    loaded = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                            text=True).stdout.strip()
    assert loaded == "[]"
