"""Float tables on disk: a CSV streamed while a run goes on, Parquet once it closes.

The file formats below the run folder (:mod:`pneumaquad.io.run_folder`, which names the
files): :class:`StreamedTable` appends blocks of float64 rows to a CSV file, flushing each
block so that an interrupted or killed run still leaves a readable file, and writes the
whole table as Parquet on close; :func:`read_table` reads either file back as one float64
array per column.

Both files are written by Arrow's C++ writers: a CSV block is formatted in one call (the
shortest text that reads back as the same double, ``nan``/``inf`` as such), so callers
should hand over blocks of rows rather than single rows.

The Parquet file describes itself: each column's field metadata holds its ``quantity``
and ``unit`` (split from the ``quantity [unit]`` name), and the file's metadata the
key/value pairs the writer passes (the run folder puts the software version, its format
version and the resolved parameters there); :func:`read_table_metadata` reads them back.
"""

from __future__ import annotations

import csv
import io
import queue
import re
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Self

import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq

__all__ = ["RowBuffer", "StreamedTable", "TableMetadata", "float64_array", "quantity_and_unit",
           "read_table", "read_table_metadata"]

_NAMED = re.compile(r"^(?P<quantity>.*\S)\s*\[(?P<unit>[^\[\]]*)\]$")


def float64_array(values: np.ndarray) -> pa.Array:
    """An Arrow float64 array viewing ``values`` (1-D; copied only if not contiguous).

    Built from the buffer, without ``pa.array``'s checks for pandas objects: the first of
    those imports pandas (about 0.2 s), which a run's first recorded block would wait on.
    NaN stays a value (not null), as with ``pa.array``.
    """
    data = np.ascontiguousarray(values, dtype=np.float64)
    if data.ndim != 1:
        raise ValueError(f"expected a 1-D array, got shape {data.shape}")
    return pa.Array.from_buffers(pa.float64(), data.shape[0], [None, pa.py_buffer(data)])


def quantity_and_unit(column: str) -> tuple[str, str]:
    """``("cap pressure", "Pa")`` from ``"cap pressure [Pa]"``; unit ``""`` without one."""
    match = _NAMED.match(column.strip())
    if match is None:
        return column.strip(), ""
    return match.group("quantity"), match.group("unit").strip()


class StreamedTable:
    """Append-only float64 table: ``csv_path`` written live, ``parquet_path`` on close.

    Use as a context manager; the Parquet file is written on exit even when the body
    raises (including ``KeyboardInterrupt``), and the exception propagates.

    Parameters
    ----------
    csv_path, parquet_path
        Files to write (their folder is created).
    columns
        Column names, ``quantity [unit]`` in SI units.
    metadata
        File-level key/value text for the Parquet file, or a callable that returns it
        when the file is written (on close).
    background
        Format and write the CSV blocks in a writer thread, so that on a machine with a
        free core the writing overlaps the computation of the next block (Arrow formats
        and writes without holding the GIL). :meth:`append` then returns before its block
        is in the file; :meth:`flush` waits for every block appended, and :meth:`close`
        (also after Ctrl-C or an error) writes them all before the Parquet file. Without
        it each block is in the file when :meth:`append` returns.
    write_csv
        False: no CSV file at all, the rows only kept for the Parquet file (a table that is
        read once and discarded, where nobody needs what a killed run leaves).
    """

    def __init__(self, csv_path: Path, parquet_path: Path, columns: Sequence[str],
                 metadata: Mapping[str, str] | Callable[[], Mapping[str, str]] | None = None,
                 background: bool = False, write_csv: bool = True) -> None:
        self.metadata = metadata
        self.csv_path = Path(csv_path)
        self.parquet_path = Path(parquet_path)
        self.csv_path.parent.mkdir(parents=True, exist_ok=True)
        self.columns: tuple[str, ...] = tuple(columns)
        if not self.columns:
            raise ValueError("at least one column is required")
        if len(set(self.columns)) != len(self.columns):
            raise ValueError(f"duplicate column names: {self.columns}")
        self._blocks: list[np.ndarray] = []
        self._rows = 0
        self._closed = False
        self._schema = pa.schema([pa.field(name, pa.float64()) for name in self.columns])
        self._file: pa.NativeFile | None = None
        self._writer: _WriterThread | None = None
        if not write_csv:
            return
        header = io.StringIO()
        csv.writer(header, lineterminator="\n").writerow(self.columns)
        # Arrow's own file: its writes go to the OS unbuffered and need no GIL.
        self._file = pa.OSFile(str(self.csv_path), "wb")
        self._file.write(header.getvalue().encode("utf-8"))
        self._csv_writer = pa_csv.CSVWriter(
            self._file, self._schema, write_options=pa_csv.WriteOptions(include_header=False))
        self._writer = _WriterThread(self._write_block, self.csv_path) if background else None

    @property
    def rows_written(self) -> int:
        """Number of rows appended so far."""
        return self._rows

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._closed

    def append(self, block: np.ndarray) -> None:
        """Append rows to the table.

        Parameters
        ----------
        block
            Array of shape ``(n, len(columns))``; a 1-D array of length
            ``len(columns)`` is taken as a single row.
        """
        if self._closed:
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
        by_column = data.T.copy()  # one contiguous array per column
        self._blocks.append(by_column)
        self._rows += data.shape[0]
        if self._writer is not None:
            self._writer.submit(by_column)
        elif self._file is not None:
            self._write_block(by_column)

    def flush(self) -> None:
        """Return when every block appended so far is in the CSV file."""
        if self._writer is not None:
            self._writer.wait()

    def _write_block(self, by_column: np.ndarray) -> None:
        """Format one block (one array per column) into the CSV file."""
        columns = [float64_array(values) for values in by_column]
        self._csv_writer.write_table(pa.Table.from_arrays(columns, schema=self._schema))

    def to_arrays(self) -> dict[str, np.ndarray]:
        """All rows appended so far, one float64 array per column: read-only views of
        the table's rows (the blocks are joined once and kept joined, so the run that
        reads its recording and the Parquet file written on close share one copy)."""
        if len(self._blocks) > 1:
            self._blocks = [np.concatenate(self._blocks, axis=1)]
        joined = self._blocks[0] if self._blocks else np.empty((len(self.columns), 0))
        by_column = joined.view()
        by_column.flags.writeable = False
        return dict(zip(self.columns, by_column, strict=True))

    def close(self) -> None:
        """Close the CSV and write the Parquet file. Idempotent."""
        if self._closed:
            return
        self._closed = True
        failure = None
        if self._writer is not None:
            failure = self._writer.stop()  # every block appended is written first
            self._writer = None
        if self._file is not None:
            self._csv_writer.close()
            self._file.close()
            self._file = None
        arrays = self.to_arrays()
        fields = []
        for name in arrays:
            quantity, unit = quantity_and_unit(name)
            fields.append(pa.field(name, pa.float64(),
                                   metadata={"quantity": quantity, "unit": unit}))
        extra = self.metadata() if callable(self.metadata) else (self.metadata or {})
        schema = pa.schema(fields, metadata={str(k): str(v) for k, v in extra.items()})
        table = pa.Table.from_arrays([float64_array(values) for values in arrays.values()],
                                     schema=schema)
        # Dictionary encoding buys nothing on float samples and costs most of the time.
        pq.write_table(table, self.parquet_path, use_dictionary=False)
        if failure is not None:  # the Parquet file holds every row even then
            raise OSError(f"writing {self.csv_path} failed: {failure}") from failure

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


def read_table(path: Path) -> dict[str, np.ndarray]:
    """Read a ``.parquet`` or ``.csv`` table as one float64 array per column.

    A CSV whose last line has no line end (a run killed in the middle of writing it)
    is read without that line.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        For an empty CSV file or numbers that cannot be read.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no recording at {path}")
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


@dataclass(frozen=True)
class TableMetadata:
    """What a recording file says about itself.

    Attributes
    ----------
    units : dict of str to str
        Column name → SI unit (``"-"`` for a dimensionless column, ``""`` if none given).
    quantities : dict of str to str
        Column name → quantity (the name without its unit).
    file : dict of str to str
        The file-level key/values of a Parquet file (empty for a CSV file).
    """

    units: dict[str, str]
    quantities: dict[str, str]
    file: dict[str, str]


def read_table_metadata(path: Path) -> TableMetadata:
    """The column units and quantities and the file metadata of a ``.parquet`` file; for
    a ``.csv`` file the units and quantities from its header names."""
    path = Path(path)
    if path.suffix == ".parquet":
        schema = pq.read_schema(path)
        units, quantities = {}, {}
        for item in schema:
            meta = {k.decode(): v.decode() for k, v in (item.metadata or {}).items()}
            quantity, unit = quantity_and_unit(item.name)
            units[item.name] = meta.get("unit", unit)
            quantities[item.name] = meta.get("quantity", quantity)
        file = {k.decode(): v.decode() for k, v in (schema.metadata or {}).items()
                if not k.startswith(b"pandas")}
        return TableMetadata(units, quantities, file)
    with path.open(newline="") as handle:
        header = next(csv.reader(handle), None) or []
    split = {name: quantity_and_unit(name) for name in header}
    return TableMetadata({n: u for n, (_, u) in split.items()},
                         {n: q for n, (q, _) in split.items()}, {})


class _WriterThread:
    """A thread that hands queued blocks to ``write`` in order (:class:`StreamedTable`'s
    ``background`` mode); the first error stops the writing and is kept for
    :meth:`stop`."""

    def __init__(self, write: Callable[[np.ndarray], None], path: Path) -> None:
        self._write = write
        self._queue: queue.Queue[np.ndarray | None] = queue.Queue()
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name=f"writer of {path.name}",
                                        daemon=True)
        self._thread.start()

    def submit(self, block: np.ndarray) -> None:
        if self.error is not None:
            raise OSError(f"writing the table failed: {self.error}") from self.error
        self._queue.put(block)

    def wait(self) -> None:
        """Return when every submitted block is written (or failed)."""
        self._queue.join()

    def stop(self) -> BaseException | None:
        """Write what is queued, end the thread; the error that stopped it, if any."""
        self._queue.put(None)
        self._thread.join()
        return self.error

    def _run(self) -> None:
        while True:
            block = self._queue.get()
            try:
                if block is None:
                    return
                if self.error is None:
                    self._write(block)
            except BaseException as error:  # kept for the thread that appends
                self.error = error
            finally:
                self._queue.task_done()


class RowBuffer:
    """Rows gathered in a preallocated block and handed to a table one block at a time.

    A recording that produces one row per control chunk fills ``row()`` in place and
    calls ``commit()``; the block goes to the table when it is full, when ``max_delay``
    seconds of wall time have passed since its first row, and on :meth:`flush` (which a
    run calls at its end, also after Ctrl-C or an error, so nothing recorded is lost).

    Parameters
    ----------
    table : StreamedTable
        Receives the blocks (:meth:`StreamedTable.append`).
    block_rows : int
        Rows per block.
    max_delay : float
        Longest wall time [s] a committed row waits before it is written.
    """

    def __init__(self, table: StreamedTable, block_rows: int = 64,
                 max_delay: float = 1.0) -> None:
        if block_rows < 1:
            raise ValueError(f"block_rows must be at least 1, got {block_rows}")
        self.table = table
        self.max_delay = max_delay
        self._block = np.full((block_rows, len(table.columns)), np.nan)
        self._count = 0
        self._first_commit = 0.0

    def row(self) -> np.ndarray:
        """The next row to fill: a view into the block, valid until :meth:`commit`."""
        return self._block[self._count]

    def commit(self) -> None:
        """Keep the row just filled; write the block when it is full or old enough."""
        now = time.perf_counter()
        if self._count == 0:
            self._first_commit = now
        self._count += 1
        if self._count == self._block.shape[0] or now - self._first_commit > self.max_delay:
            self.flush()

    def flush(self) -> None:
        """Hand the committed rows to the table (a no-op when there are none)."""
        if self._count:
            self.table.append(self._block[: self._count])
            self._count = 0
