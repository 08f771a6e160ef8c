"""Append-only per-packet log of a co-simulation peer (the data behind the timing analysis).

The thesis timestamped packets on the target, had SrLib return them and studied the
travel times and pauses, with Wireshark for the per-packet view (Daepp 2011, ch. 5.3.1,
Fig. 37). Here every peer logs each datagram it sends or receives into preallocated
NumPy columns (one scalar write per column, no per-packet objects); the analysis in
:mod:`pneumaquad.network.timing` runs on the arrays. Files use columns named
``quantity [unit]`` like every recording of the package.
"""

from __future__ import annotations

import math
from enum import IntEnum
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq

from pneumaquad.network.wire import HEADER, HEADER_SIZE, REASONS, Message, MessageType

SENT = 0
RECEIVED = 1
_DIRECTIONS = ("sent", "received")


class Classification(IntEnum):
    """What the receiver made of a packet; malformed codes are 10 + index in ``REASONS``."""

    OK = 0
    DUPLICATE = 1
    REORDERED = 2
    LATE = 3
    TRUNCATED = 10
    OVERSIZED = 11
    BAD_MAGIC = 12
    BAD_VERSION = 13
    UNKNOWN_TYPE = 14
    BAD_COUNT = 15
    NON_FINITE = 16


#: ``ProtocolError.reason`` -> classification code.
MALFORMED_CODES = {reason: Classification[reason.upper()] for reason in REASONS}
MALFORMED_MIN = int(Classification.TRUNCATED)

#: Column name in files -> (attribute, dtype, fill value).
COLUMNS = {
    "direction [-]": ("direction", np.int8, 0),
    "sequence [-]": ("sequence", np.int64, -1),
    "message type [-]": ("message_type", np.int16, 0),
    "send time [s]": ("send_time", np.float64, math.nan),
    "receive time [s]": ("receive_time", np.float64, math.nan),
    "size [B]": ("size", np.int32, 0),
    "classification [-]": ("classification", np.int16, 0),
    "answered sequence [-]": ("answered_sequence", np.int64, -1),
    "echoed time [s]": ("echoed_time", np.float64, math.nan),
}


class _Column:
    """Read-only trimmed view of one column of a :class:`PacketLog`."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, log: PacketLog, owner: type | None = None) -> np.ndarray:
        return log._arrays[self.name][: log._length]


class PacketLog:
    """Growable columns of per-packet records.

    Columns (attributes, trimmed views): ``direction`` (:data:`SENT`/:data:`RECEIVED`),
    ``sequence`` (-1 when malformed), ``message_type`` (0 when malformed), ``send_time``
    [s] (local clock for sent packets, the header's sender time for received ones),
    ``receive_time`` [s] (local monotonic clock; NaN for sent packets), ``size`` [B],
    ``classification`` (:class:`Classification`), ``answered_sequence`` (a ``STATE``'s
    answered command, else -1) and ``echoed_time`` [s] (a ``PONG``'s echoed ping time,
    else NaN).

    Parameters
    ----------
    capacity
        Initial number of rows; doubled whenever full.
    """

    direction = _Column()
    sequence = _Column()
    message_type = _Column()
    send_time = _Column()
    receive_time = _Column()
    size = _Column()
    classification = _Column()
    answered_sequence = _Column()
    echoed_time = _Column()

    def __init__(self, capacity: int = 4096) -> None:
        capacity = max(int(capacity), 1)
        self._length = 0
        self._arrays = {attr: np.full(capacity, fill, dtype=dtype)
                        for attr, dtype, fill in COLUMNS.values()}

    def __len__(self) -> int:
        return self._length

    def _grow(self) -> None:
        for attr, dtype, fill in COLUMNS.values():
            old = self._arrays[attr]
            new = np.full(2 * old.size, fill, dtype=dtype)
            new[: old.size] = old
            self._arrays[attr] = new

    def append(self, direction: int, sequence: int, message_type: int, send_time: float,
               receive_time: float, size: int, classification: int = 0,
               answered_sequence: int = -1, echoed_time: float = math.nan) -> None:
        """Append one record (scalars only; see the class docstring for the fields)."""
        row = self._length
        arrays = self._arrays
        if row == arrays["direction"].size:
            self._grow()
        arrays["direction"][row] = direction
        arrays["sequence"][row] = sequence
        arrays["message_type"][row] = message_type
        arrays["send_time"][row] = send_time
        arrays["receive_time"][row] = receive_time
        arrays["size"][row] = size
        arrays["classification"][row] = classification
        arrays["answered_sequence"][row] = answered_sequence
        arrays["echoed_time"][row] = echoed_time
        self._length = row + 1

    def record_sent(self, datagram: bytes, send_time: float | None = None) -> None:
        """Log a datagram this peer sent (parses its header, no full decode).

        Parameters
        ----------
        datagram
            Bytes as sent (a valid datagram of this protocol).
        send_time
            Local monotonic clock at sending [s]; defaults to the header's sender time.
        """
        _, _, type_code, sequence, sender_time, count, _ = HEADER.unpack_from(datagram)
        answered, echoed = -1, math.nan
        if type_code == MessageType.STATE:
            offset = HEADER_SIZE + 8 * (count - 2)
            answered = int(np.frombuffer(datagram, "<f8", 1, offset)[0])
        elif type_code == MessageType.PONG:
            echoed = float(np.frombuffer(datagram, "<f8", 1, HEADER_SIZE)[0])
        self.append(SENT, sequence, type_code, sender_time if send_time is None else send_time,
                    math.nan, len(datagram), 0, answered, echoed)

    def record_received(self, message: Message, size: int, receive_time: float,
                        classification: int = Classification.OK) -> None:
        """Log a decoded datagram this peer received.

        Parameters
        ----------
        message
            The decoded message.
        size
            Datagram size [B].
        receive_time
            Local monotonic clock at reception [s].
        classification
            ``OK``, ``DUPLICATE``, ``REORDERED`` or ``LATE``.
        """
        answered, echoed = -1, math.nan
        if message.type == MessageType.STATE:
            answered = int(message.values[-2])
        elif message.type == MessageType.PONG:
            echoed = float(message.values[0])
        self.append(RECEIVED, message.sequence, message.type, message.sender_time,
                    receive_time, size, classification, answered, echoed)

    def record_malformed(self, reason: str, size: int, receive_time: float) -> None:
        """Log a received datagram that :func:`~pneumaquad.network.wire.decode` rejected."""
        self.append(RECEIVED, -1, 0, math.nan, receive_time, size, MALFORMED_CODES[reason])

    def columns(self) -> dict[str, np.ndarray]:
        """Trimmed copies of the columns, keyed by file column name (``quantity [unit]``)."""
        return {name: self._arrays[attr][: self._length].copy()
                for name, (attr, _, _) in COLUMNS.items()}

    def to_table(self) -> pa.Table:
        """The log as a pyarrow table; direction, type and classification as names."""
        data = self.columns()
        table = {name: pa.array(values) for name, values in data.items()}
        table["direction [-]"] = pa.array(np.array(_DIRECTIONS)[data["direction [-]"]])
        names = {int(t): t.name for t in MessageType} | {0: "MALFORMED"}
        table["message type [-]"] = pa.array([names.get(int(t), str(int(t)))
                                              for t in data["message type [-]"]], pa.string())
        table["classification [-]"] = pa.array(
            [Classification(int(c)).name for c in data["classification [-]"]], pa.string())
        return pa.table(table)

    def write(self, path: Path | str) -> Path:
        """Write the log to ``.parquet`` or ``.csv`` (by suffix) and return the path."""
        path = Path(path)
        if path.suffix == ".parquet":
            pq.write_table(self.to_table(), path)
        elif path.suffix == ".csv":
            pa_csv.write_csv(self.to_table(), path)
        else:
            raise ValueError(f"unknown packet log format {path.suffix!r} (.parquet or .csv)")
        return path

    @classmethod
    def read(cls, path: Path | str) -> PacketLog:
        """Read a log written by :meth:`write`."""
        path = Path(path)
        table = pq.read_table(path) if path.suffix == ".parquet" else pa_csv.read_csv(path)
        data = table.to_pydict()
        log = cls(capacity=len(table))
        types = {t.name: int(t) for t in MessageType} | {"MALFORMED": 0}
        for name, (attr, dtype, fill) in COLUMNS.items():
            values = data[name]
            if name == "direction [-]":
                values = [_DIRECTIONS.index(v) for v in values]
            elif name == "message type [-]":
                values = [types[v] for v in values]
            elif name == "classification [-]":
                values = [int(Classification[v]) for v in values]
            column = np.array([fill if v is None else v for v in values], dtype=dtype)
            log._arrays[attr][: column.size] = column
        log._length = len(table)
        return log
