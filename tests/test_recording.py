"""Tests of run folders, recordings, summaries and plots."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest

from pneumaquad.io.run_folder import (
    RunFolderWriter,
    RunRecorder,
    create_run_folder,
    read_recording,
)
from pneumaquad.io.tables import float64_array
from pneumaquad.reporting import plotting

COLUMNS = ["time [s]", "position [m]", "cap pressure [Pa]"]


def _block(start: int, n: int) -> np.ndarray:
    t = np.arange(start, start + n) * 1e-3
    return np.column_stack([t, np.sin(t) / 3.0, 101325.0 + np.pi * t])


def test_create_run_folder_generated_names_are_unique(tmp_path: Path) -> None:
    first = create_run_folder(None, "step", base=tmp_path)
    second = create_run_folder(None, "step", base=tmp_path)
    assert first != second
    assert first.is_dir() and second.is_dir()
    assert first.parent == tmp_path and first.name.startswith("step-")


def test_create_run_folder_explicit_output(tmp_path: Path) -> None:
    out = tmp_path / "a" / "b"
    assert create_run_folder(out, "step") == out
    assert out.is_dir()
    assert create_run_folder(out, "step") == out  # existing folder is fine


def test_csv_readable_before_close(tmp_path: Path) -> None:
    recorder = RunRecorder(tmp_path, COLUMNS)
    block = _block(0, 5)
    recorder.append(block)
    recorder.append(_block(5, 3))
    assert recorder.rows_written == 8
    with (tmp_path / "recording.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == COLUMNS
    assert len(rows) == 9
    # Full precision: values round-trip exactly.
    np.testing.assert_array_equal(np.array(rows[1:6], dtype=float), block)
    assert not (tmp_path / "recording.parquet").exists()
    data = read_recording(tmp_path)  # falls back to CSV
    assert data["time [s]"].shape == (8,)
    recorder.close()


def test_parquet_equals_csv_after_close(tmp_path: Path) -> None:
    with RunRecorder(tmp_path, COLUMNS) as recorder:
        recorder.append(_block(0, 10))
        recorder.append(_block(10, 1)[0])  # a single 1-D row
    assert recorder.closed
    from_parquet = read_recording(tmp_path / "recording.parquet")
    from_csv = read_recording(tmp_path / "recording.csv")
    assert list(from_parquet) == COLUMNS == list(from_csv)
    for name in COLUMNS:
        np.testing.assert_array_equal(from_parquet[name], from_csv[name])
        assert from_parquet[name].dtype == np.float64
    np.testing.assert_array_equal(read_recording(tmp_path)["time [s]"], _block(0, 11)[:, 0])


def test_exception_inside_with_leaves_files_and_reraises(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError, match="boom"), RunRecorder(tmp_path, COLUMNS) as recorder:
        recorder.append(_block(0, 4))
        raise RuntimeError("boom")
    assert (tmp_path / "recording.csv").exists()
    assert (tmp_path / "recording.parquet").exists()
    assert read_recording(tmp_path / "recording.parquet")["position [m]"].shape == (4,)


def test_keyboard_interrupt_is_not_swallowed(tmp_path: Path) -> None:
    with pytest.raises(KeyboardInterrupt), RunRecorder(tmp_path, COLUMNS) as recorder:
        recorder.append(_block(0, 2))
        raise KeyboardInterrupt
    assert read_recording(tmp_path)["time [s]"].shape == (2,)


def test_empty_recording_and_bad_shapes(tmp_path: Path) -> None:
    with RunRecorder(tmp_path, COLUMNS) as recorder, pytest.raises(ValueError):
        recorder.append(np.zeros((2, 2)))
    assert recorder.rows_written == 0
    assert read_recording(tmp_path)["time [s]"].shape == (0,)
    assert read_recording(tmp_path / "recording.csv")["time [s]"].shape == (0,)
    with pytest.raises(RuntimeError):
        recorder.append(_block(0, 1))


def test_summary_handles_numpy_and_nan(tmp_path: Path) -> None:
    path = RunFolderWriter(tmp_path).write_summary(
        {
            "rmse [m]": np.float64(0.0012),
            "steps": np.int64(3),
            "ok": np.bool_(True),
            "missing": float("nan"),
            "series": np.array([1.0, np.nan, np.inf]),
            "nested": {"gain": np.float32(0.5), "path": tmp_path},
        },
    )
    assert path == tmp_path / "summary.json"
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    loaded = json.loads(text)
    assert loaded["rmse [m]"] == 0.0012
    assert loaded["steps"] == 3
    assert loaded["ok"] is True
    assert loaded["missing"] is None
    assert loaded["series"] == [1.0, None, None]
    assert loaded["nested"]["gain"] == 0.5
    assert loaded["nested"]["path"] == str(tmp_path)


def _synthetic_recording(n: int = 400, delay: float = 0.0) -> dict[str, np.ndarray]:
    psi = 6894.757
    t = np.linspace(0.0, 4.0, n)
    command = np.where(t < 1.0, 0.25, 6.5)
    position = 0.1 * (1.0 - np.exp(-np.clip(t - 1.0 - delay, 0.0, None) / 0.3))
    return {
        "time [s]": t,
        "command [V]": command,
        "reference position [m]": np.where(t < 1.0, 0.0, 0.1),
        "position [m]": position,
        "cap pressure [Pa]": (14.7 + 50.0 * position / 0.1) * psi,
        "rod pressure [Pa]": (64.7 - 45.0 * position / 0.1) * psi,
        "supply pressure [Pa]": np.full(n, 64.7 * psi),
    }


def test_plots_write_png(tmp_path: Path) -> None:
    rec = _synthetic_recording()
    png_magic = b"\x89PNG"
    out = plotting.plot_rig_run(rec, tmp_path / "run.png", title="Synthetic step")
    assert out.read_bytes()[:4] == png_magic and out.stat().st_size > 1000

    minimal = {"time [s]": rec["time [s]"], "position [m]": rec["position [m]"]}
    out = plotting.plot_rig_run(minimal, tmp_path / "minimal.png")
    assert out.stat().st_size > 1000

    out = plotting.plot_comparison(
        {"measured": rec, "simulated": _synthetic_recording(300, delay=0.1)},
        tmp_path / "sub" / "cmp.png",
        title="Comparison",
    )
    assert out.read_bytes()[:4] == png_magic and out.stat().st_size > 1000

    v = np.linspace(-0.5, 0.5, 201)
    f = 13.3 * np.tanh(40 * v) + 2.2 * v
    out = plotting.plot_friction_curve(
        {"model": (v, f), "scaled": (v, 0.8 * f)}, tmp_path / "f.png"
    )
    assert out.read_bytes()[:4] == png_magic and out.stat().st_size > 1000


def test_plot_requires_time(tmp_path: Path) -> None:
    with pytest.raises(KeyError):
        plotting.plot_rig_run({"position [m]": np.zeros(3)}, tmp_path / "x.png")


def test_csv_tolerates_truncated_last_line_and_nan(tmp_path: Path) -> None:
    with RunRecorder(tmp_path, COLUMNS) as recorder:
        recorder.append(np.array([[0.0, np.nan, np.inf], [1e-3, 0.5, 2.0]]))
    with (tmp_path / "recording.csv").open("a") as handle:
        handle.write("0.002,0.12")  # as if killed mid-write
    data = read_recording(tmp_path / "recording.csv")
    assert data["time [s]"].tolist() == [0.0, 1e-3]
    assert np.isnan(data["position [m]"][0]) and np.isinf(data["cap pressure [Pa]"][0])


def test_background_writer_keeps_every_block_in_order(tmp_path: Path) -> None:
    recorder = RunRecorder(tmp_path, COLUMNS, background=True)
    for start in range(0, 200, 7):
        recorder.append(_block(start, 7))
    recorder.flush()  # every block appended so far is in the file now
    with (tmp_path / "recording.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    np.testing.assert_array_equal(np.array(rows[1:], dtype=float), _block(0, 203))
    recorder.close()
    np.testing.assert_array_equal(read_recording(tmp_path / "recording.parquet")["time [s]"],
                                  _block(0, 203)[:, 0])


def test_background_writer_writes_everything_when_the_run_fails(tmp_path: Path) -> None:
    with pytest.raises(KeyboardInterrupt), RunRecorder(tmp_path, COLUMNS,
                                                       background=True) as recorder:
        for start in range(0, 1000, 100):
            recorder.append(_block(start, 100))
        raise KeyboardInterrupt
    for name in ("recording.csv", "recording.parquet"):
        data = read_recording(tmp_path / name)
        np.testing.assert_array_equal(data["position [m]"], _block(0, 1000)[:, 1])


def test_csv_holds_special_values_exactly(tmp_path: Path) -> None:
    values = np.array([[0.1, np.nan, -np.inf], [5e-324, 1.7976931348623157e308, -0.0],
                       [1 / 3, np.pi * 1e-12, 123456789.123456789]])
    with RunRecorder(tmp_path, COLUMNS) as recorder:
        recorder.append(values)
    data = read_recording(tmp_path / "recording.csv")
    np.testing.assert_array_equal(np.column_stack([data[name] for name in COLUMNS]), values)


def test_row_buffer_writes_full_blocks_and_the_rest_on_flush(tmp_path: Path) -> None:
    from pneumaquad.io.tables import RowBuffer

    recorder = RunRecorder(tmp_path, COLUMNS)
    rows = RowBuffer(recorder, block_rows=4, max_delay=3600.0)
    expected = _block(0, 10)
    for index in range(10):
        rows.row()[:] = expected[index]
        rows.commit()
        assert recorder.rows_written == 4 * ((index + 1) // 4)  # whole blocks only
    rows.flush()
    assert recorder.rows_written == 10
    recorder.close()
    np.testing.assert_array_equal(read_recording(tmp_path)["cap pressure [Pa]"], expected[:, 2])


def test_row_buffer_writes_a_row_that_waited_too_long(tmp_path: Path) -> None:
    from pneumaquad.io.tables import RowBuffer

    with RunRecorder(tmp_path, COLUMNS) as recorder:
        rows = RowBuffer(recorder, block_rows=1000, max_delay=0.0)
        rows.row()[:] = _block(0, 1)[0]
        rows.commit()
        rows.row()[:] = _block(1, 1)[0]
        rows.commit()  # the first row has waited longer than max_delay: both go out
        assert recorder.rows_written == 2


def test_float64_array_views_the_values_with_nan_as_a_value() -> None:
    values = np.array([1.5, np.nan, -np.inf, 0.1])
    array = float64_array(values[::1])
    assert array.type == pa.float64()
    assert array.null_count == 0
    np.testing.assert_array_equal(array.to_numpy(), values)
    strided = float64_array(np.arange(6.0)[::2])  # copied to a contiguous buffer
    np.testing.assert_array_equal(strided.to_numpy(), [0.0, 2.0, 4.0])
    with pytest.raises(ValueError, match="1-D"):
        float64_array(np.zeros((2, 2)))


def test_writing_a_table_does_not_import_pandas(tmp_path: Path) -> None:
    """Arrow's pa.array imports pandas on its first call (about 0.2 s, which a run's first
    recorded block would wait on); the tables are built without it."""
    code = ("import sys, numpy as np; from pneumaquad.io.tables import StreamedTable; "
            f"t = StreamedTable({str(tmp_path / 'a.csv')!r}, {str(tmp_path / 'a.parquet')!r}, "
            "['time [s]', 'x [m]'], background=True); t.append(np.ones((3, 2))); t.close(); "
            "print('pandas' in sys.modules)")
    loaded = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                            text=True).stdout.strip()
    assert loaded == "False"
