"""Run folders, streamed recordings and run summaries.

A run writes its time series to ``recording.csv`` while it runs (one flushed
block at a time, so an interrupted run still leaves a readable file) and to
``recording.parquet`` once it closes. Columns are named ``quantity [unit]``
in SI units, e.g. ``"time [s]"``, ``"position [m]"``, ``"cap pressure [Pa]"``.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping, Sequence
from datetime import datetime
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

CSV_NAME = "recording.csv"
PARQUET_NAME = "recording.parquet"
SUMMARY_NAME = "summary.json"


def create_run_folder(output: Path | None, kind: str, base: Path = Path("runs")) -> Path:
    """Create the folder a run writes into.

    Parameters
    ----------
    output
        Folder requested by the user. Created if missing; an existing folder is
        reused and its recording files will be overwritten.
    kind
        Run kind used in the generated name, e.g. ``"rig-step"``.
    base
        Parent of generated folders when ``output`` is ``None``.

    Returns
    -------
    Path
        ``output``, or ``base / f"{kind}-{YYYYmmdd-HHMMSS}"`` with a ``-2``,
        ``-3``, ... suffix appended if that name is already taken.
    """
    if output is not None:
        output = Path(output)
        output.mkdir(parents=True, exist_ok=True)
        return output
    base = Path(base)
    base.mkdir(parents=True, exist_ok=True)
    stem = f"{kind}-{datetime.now():%Y%m%d-%H%M%S}"
    candidate = base / stem
    suffix = 1
    while True:
        try:
            candidate.mkdir()
        except FileExistsError:
            suffix += 1
            candidate = base / f"{stem}-{suffix}"
        else:
            return candidate


class RunRecorder:
    """Append-only recorder writing ``recording.csv`` live and ``recording.parquet`` on close.

    Use as a context manager; the Parquet file is written on exit even when the
    body raises (including ``KeyboardInterrupt``), and the exception propagates.

    Parameters
    ----------
    folder
        Run folder (must exist or be creatable).
    columns
        Column names, ``quantity [unit]`` in SI units.
    """

    def __init__(self, folder: Path, columns: Sequence[str]) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.columns: tuple[str, ...] = tuple(columns)
        if not self.columns:
            raise ValueError("at least one column is required")
        if len(set(self.columns)) != len(self.columns):
            raise ValueError(f"duplicate column names: {self.columns}")
        self.csv_path = self.folder / CSV_NAME
        self.parquet_path = self.folder / PARQUET_NAME
        self._blocks: list[np.ndarray] = []
        self._rows = 0
        self._closed = False
        self._file: io.TextIOWrapper | None = self.csv_path.open("w", newline="")
        csv.writer(self._file).writerow(self.columns)
        self._file.flush()

    @property
    def rows_written(self) -> int:
        """Number of rows appended so far."""
        return self._rows

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._closed

    def append(self, block: np.ndarray) -> None:
        """Append rows to the recording.

        Parameters
        ----------
        block
            Array of shape ``(n, len(columns))``; a 1-D array of length
            ``len(columns)`` is taken as a single row.
        """
        if self._file is None:
            raise RuntimeError("recorder is closed")
        data = np.asarray(block, dtype=np.float64)
        if data.ndim == 1:
            data = data.reshape(1, -1)
        if data.ndim != 2 or data.shape[1] != len(self.columns):
            raise ValueError(
                f"expected a block of shape (n, {len(self.columns)}), got {np.shape(block)}"
            )
        if data.shape[0] == 0:
            return
        np.savetxt(self._file, data, delimiter=",", fmt="%.17g")
        self._file.flush()
        self._blocks.append(data.copy())
        self._rows += data.shape[0]

    def to_arrays(self) -> dict[str, np.ndarray]:
        """All rows appended so far, one float64 array per column."""
        if self._blocks:
            table = np.concatenate(self._blocks, axis=0)
        else:
            table = np.empty((0, len(self.columns)))
        return {name: table[:, i].copy() for i, name in enumerate(self.columns)}

    def close(self) -> None:
        """Close the CSV and write ``recording.parquet``. Idempotent."""
        if self._closed:
            return
        self._closed = True
        if self._file is not None:
            self._file.close()
            self._file = None
        arrays = self.to_arrays()
        table = pa.table(
            {name: pa.array(values, type=pa.float64()) for name, values in arrays.items()}
        )
        pq.write_table(table, self.parquet_path)

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def __del__(self) -> None:
        # Never leave a dangling handle; the Parquet file is only written by close().
        file = getattr(self, "_file", None)
        if file is not None:
            file.close()


def jsonable(value: Any) -> Any:
    """Convert numpy types, paths and non-finite floats to JSON-friendly values."""
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    return value


def write_summary(folder: Path, summary: Mapping[str, Any]) -> Path:
    """Write ``summary.json`` into ``folder``.

    numpy scalars and arrays become plain numbers and lists; NaN and ±inf
    become ``null``; paths become strings.

    Returns
    -------
    Path
        Path of the written file.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / SUMMARY_NAME
    text = json.dumps(jsonable(summary), indent=2, allow_nan=False)
    path.write_text(text + "\n")
    return path


def read_recording(folder_or_file: Path) -> dict[str, np.ndarray]:
    """Read a recording as one float64 array per column.

    Parameters
    ----------
    folder_or_file
        A run folder (Parquet preferred, CSV as fallback) or a
        ``.parquet``/``.csv`` file.
    """
    path = Path(folder_or_file)
    if path.is_dir():
        parquet = path / PARQUET_NAME
        path = parquet if parquet.exists() else path / CSV_NAME
    if not path.exists():
        raise FileNotFoundError(f"no recording at {folder_or_file}")
    if path.suffix == ".parquet":
        table = pq.read_table(path)
        return {
            name: np.asarray(table.column(name).to_numpy(), dtype=np.float64)
            for name in table.column_names
        }
    with path.open(newline="") as handle:
        header = next(csv.reader(handle), None)
        if header is None:
            raise ValueError(f"empty recording file {path}")
        text = handle.read()
    lines = text.splitlines()
    # Every complete row ends with a newline; a run killed mid-write may leave
    # a truncated, unterminated last line, which is dropped.
    if lines and not text.endswith(("\n", "\r")):
        lines.pop()
    lines = [line for line in lines if line.strip()]
    if lines:
        data = np.loadtxt(lines, delimiter=",", dtype=np.float64, ndmin=2)
    else:
        data = np.empty((0, len(header)))
    return {name: data[:, i].copy() for i, name in enumerate(header)}
