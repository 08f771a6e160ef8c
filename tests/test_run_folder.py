"""The run folder contract (pneumaquad.io.run_folder, docs/run-folder.md): one writer, one
reader, a format version, one strict-JSON check for every summary write."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

from pneumaquad.io import run_folder
from pneumaquad.io.run_folder import (
    FORMAT_KEY,
    FORMAT_VERSION,
    RunFolderError,
    RunFolderVersionError,
    RunFolderWriter,
    drawing_plots,
    read_recording,
    read_run_folder,
    scratch_run_folders,
)
from pneumaquad.params import load_rig

COLUMNS = ["time [s]", "position [m]", "cap pressure [Pa]"]
PACKAGE = Path(__file__).resolve().parents[1] / "src" / "pneumaquad"


def _rows(start: int, n: int) -> np.ndarray:
    t = np.arange(start, start + n) * 1e-3
    return np.column_stack([t, np.sin(t), 101325.0 + t])


def _write_run(folder: Path, summary: dict | None = None) -> RunFolderWriter:
    writer = RunFolderWriter(folder)
    writer.write_parameters(load_rig("thesis-rig"))
    with writer.recorder(COLUMNS) as recorder:
        recorder.append(_rows(0, 5))
        recorder.append(_rows(5, 3))
    writer.write_summary(summary or {"description": "round trip", "steps": np.int64(8)})
    return writer


def test_what_the_writer_writes_the_reader_reads(tmp_path: Path) -> None:
    _write_run(tmp_path, {"description": "round trip", "steps": np.int64(8),
                          "rmse [m]": np.float64(1.5e-3), "nested": {"a": [1, 2]}})
    run = read_run_folder(tmp_path)
    assert run.version == FORMAT_VERSION and run.kind == "rig" and run.notes == []
    assert run.summary[FORMAT_KEY] == FORMAT_VERSION
    assert run.summary["steps"] == 8 and run.summary["rmse [m]"] == 1.5e-3
    assert run.summary["nested"] == {"a": [1, 2]}
    assert run.recording_file.name == "recording.parquet"
    assert list(run.recording) == COLUMNS
    np.testing.assert_array_equal(run.recording["position [m]"], _rows(0, 8)[:, 1])
    assert load_rig(run.parameters_file) == load_rig("thesis-rig")
    assert "[rig]" in run.parameters
    assert run.timing is None and run.model_file is None and run.trajectory_file is None
    # the version key comes first, where a reader of the file sees it
    assert next(iter(json.loads((tmp_path / "summary.json").read_text()))) == FORMAT_KEY


def test_robot_and_network_files_round_trip(tmp_path: Path) -> None:
    writer = _write_run(tmp_path)
    writer.write_model("<mujoco/>")
    writer.write_trajectory(np.arange(3.0), np.zeros((3, 7)))
    writer.write_timing({"rtt p99 [s]": np.float64(2e-4), "lost": float("nan")})
    run = read_run_folder(tmp_path)
    assert run.model_file == tmp_path / "model.xml"
    with np.load(run.trajectory_file) as trajectory:
        assert trajectory["qpos"].shape == (3, 7)
    assert run.timing == {"rtt p99 [s]": 2e-4, "lost": None}


def test_a_newer_format_is_refused_naming_the_version(tmp_path: Path) -> None:
    _write_run(tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text())
    summary[FORMAT_KEY] = FORMAT_VERSION + 1
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    message = f"run folder format {FORMAT_VERSION + 1}; this pneumaquad reads format " \
              f"{FORMAT_VERSION}"
    with pytest.raises(RunFolderVersionError, match=message):
        read_run_folder(tmp_path)
    with pytest.raises(RunFolderVersionError, match=message):
        read_recording(tmp_path)  # reading only the recording of the folder checks it too
    summary[FORMAT_KEY] = "one"
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    with pytest.raises(RunFolderVersionError, match="'one'; expected a whole number"):
        read_run_folder(tmp_path)


def test_a_folder_without_the_key_reads_as_format_1(tmp_path: Path) -> None:
    _write_run(tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text())
    del summary[FORMAT_KEY]  # as every run folder written before the key existed
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    run = read_run_folder(tmp_path)
    assert run.version == 1 and run.summary["description"] == "round trip"


def test_a_nan_in_an_update_is_treated_as_at_the_first_write(tmp_path: Path) -> None:
    writer = _write_run(tmp_path, {"first": float("nan"), "series": np.array([1.0, np.inf])})
    summary = writer.update_summary({"walking": {"smallest margin [m]": np.float64(np.nan),
                                                 "ok": np.bool_(True)}})
    text = (tmp_path / "summary.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert summary["first"] is None and summary["series"] == [1.0, None]
    assert summary["walking"] == {"smallest margin [m]": None, "ok": True}
    assert summary == read_run_folder(tmp_path).summary
    # a value JSON cannot hold is refused at the first write and in an update alike, and
    # the file on disk stays as it was
    for write in (writer.write_summary, writer.update_summary):
        with pytest.raises(TypeError, match=r"summary / walking: <object .*> \(of type object"):
            write({"walking": object()})
        assert (tmp_path / "summary.json").read_text() == text


def test_an_interrupted_run_folder_is_readable(tmp_path: Path) -> None:
    # a run killed while it ran: parameters, a CSV whose last line was cut, no Parquet
    writer = RunFolderWriter(tmp_path)
    writer.write_parameters(load_rig("thesis-rig"))
    recorder = writer.recorder(COLUMNS)
    recorder.append(_rows(0, 4))
    with (tmp_path / "recording.csv").open("a") as handle:
        handle.write("0.004,0.12")
    run = read_run_folder(tmp_path)
    assert run.version == 1 and run.summary == {}
    assert run.recording_file.name == "recording.csv"
    assert run.recording["time [s]"].size == 4
    assert any("summary.json is missing" in note for note in run.notes)
    # Ctrl-C: the recorder closes (Parquet) and the summary says so
    recorder.close()
    writer.write_summary({"interrupted": True})
    run = read_run_folder(tmp_path)
    assert run.summary["interrupted"] is True and run.recording_file.name == "recording.parquet"


@pytest.mark.parametrize(("make", "message"), [
    (lambda folder: None, "does not exist"),
    (lambda folder: folder.mkdir(), r"no parameters\.toml"),
    (lambda folder: (folder.mkdir(), (folder / "parameters.toml").write_text("[meta]\n")),
     "neither a \\[rig\\] table"),
])
def test_folders_that_are_not_run_folders(tmp_path: Path, make, message: str) -> None:
    folder = tmp_path / "run"
    make(folder)
    with pytest.raises(RunFolderError, match=message):
        read_run_folder(folder)


def test_only_the_run_folder_module_names_the_files() -> None:
    names = {value for key, value in vars(run_folder).items()
             if key.endswith("_NAME") and isinstance(value, str)}
    assert {"summary.json", "parameters.toml", "recording.csv", "recording.parquet"} <= names
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path == PACKAGE / "io" / "run_folder.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and node.value in names:
                offenders.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {node.value}")
            if (isinstance(node, ast.Attribute) and node.attr in ("load", "loads", "dump", "dumps")
                    and isinstance(node.value, ast.Name) and node.value.id == "json"):
                offenders.append(f"{path.relative_to(PACKAGE)}:{node.lineno} json.{node.attr}")
    allowed = {"reporting/cost_report.py",  # report files, not run folders
               "robot/video_worker.py",  # messages on the video worker's pipes, not files
               "robot/video_process.py",  # the worker process's side of those pipes
               "interop/fmu_model.py"}  # the resources inside an FMU, not a run folder
    assert [o for o in offenders if o.split(":")[0] not in allowed] == []


def test_the_parquet_recording_describes_itself(tmp_path: Path) -> None:
    """Units per column, the resolved parameters, software and format versions travel in
    the Parquet file's metadata and read back equal to what was written."""
    import pneumaquad
    from pneumaquad.io.run_folder import FORMAT_VERSION, RunFolderWriter, read_run_folder
    from pneumaquad.io.tables import read_table_metadata
    from pneumaquad.params import load_rig

    writer = RunFolderWriter(tmp_path / "run")
    writer.write_parameters(load_rig("thesis-rig"))
    columns = ("time [s]", "cap pressure [Pa]", "piston velocity [m/s]", "control mode [-]")
    with writer.recorder(columns) as recorder:
        recorder.append(np.array([[0.0, 1e5, 0.01, 1.0], [0.001, 1.1e5, 0.02, 1.0]]))
    writer.write_summary({"description": "metadata"})
    run = read_run_folder(tmp_path / "run")
    assert run.recording_file.suffix == ".parquet"
    assert run.units == {"time [s]": "s", "cap pressure [Pa]": "Pa",
                         "piston velocity [m/s]": "m/s", "control mode [-]": "-"}
    metadata = read_table_metadata(run.recording_file)
    assert metadata.quantities["cap pressure [Pa]"] == "cap pressure"
    assert metadata.file["pneumaquad version"] == pneumaquad.__version__
    assert metadata.file["run folder format"] == str(FORMAT_VERSION)
    assert metadata.file["parameters.toml"] == run.parameters
    csv_units = read_table_metadata(tmp_path / "run" / "recording.csv").units
    assert csv_units == run.units


def test_read_run_reads_a_folder_with_its_units_and_parameters(tmp_path: Path) -> None:
    """``pneumaquad.read_run`` (the earlier ``read_run_folder`` still works): the resolved
    parameters carried in the Parquet metadata validate into the parameters written."""
    import pneumaquad
    from pneumaquad.io.tables import read_table_metadata

    _write_run(tmp_path / "run")
    run = pneumaquad.read_run(tmp_path / "run")
    assert pneumaquad.read_run_folder is pneumaquad.read_run
    assert str(tmp_path / "run") == str(run.path)
    assert run.units == {"time [s]": "s", "position [m]": "m", "cap pressure [Pa]": "Pa"}
    assert run.summary["description"] == "round trip"
    copied = tmp_path / "from-metadata.toml"
    copied.write_text(read_table_metadata(run.recording_file).file["parameters.toml"],
                      encoding="utf-8")
    assert load_rig(copied) == load_rig("thesis-rig") == load_rig(run.parameters_file)


def test_a_scratch_run_folder_has_its_recording_as_parquet_only(tmp_path: Path) -> None:
    """Inside scratch_run_folders a recording skips its CSV file (and plots are not
    drawn); the Parquet file holds every row; outside, and after an error inside, both
    are back."""
    assert drawing_plots()
    with scratch_run_folders():
        assert not drawing_plots()
        _write_run(tmp_path / "scratch")
    assert drawing_plots()
    assert not (tmp_path / "scratch" / "recording.csv").exists()
    run = read_run_folder(tmp_path / "scratch")
    np.testing.assert_array_equal(run.recording["cap pressure [Pa]"], _rows(0, 8)[:, 2])
    with pytest.raises(RuntimeError), scratch_run_folders():
        raise RuntimeError("a failing case")
    assert drawing_plots()
    _write_run(tmp_path / "kept")
    assert (tmp_path / "kept" / "recording.csv").is_file()
