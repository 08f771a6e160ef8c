"""A UDP endpoint of the co-simulation protocol: bound socket, per-peer tracking, packet log.

Every received datagram goes through :func:`~pneumaquad.network.timing.accept_datagram`
(malformed, duplicate and reordered datagrams are dropped, counted and logged); nothing a
peer sends can make :meth:`UdpEndpoint.receive` raise. A ``HELLO`` whose parameters are
invalid, or differ from the endpoint's own ``hello_dimensions``, is refused the same way
(reason ``bad_count``) and its sender remembered in :attr:`UdpEndpoint.refused_hellos`.
The socket binds to 127.0.0.1 unless another address is given explicitly; with a ``peer``
filter, datagrams from any other address are dropped and counted (``foreign``) before
they are even decoded.
"""

from __future__ import annotations

import select
import socket
import time
from collections import deque

from pneumaquad.network.packet_log import PacketLog
from pneumaquad.network.protocol import check_hello
from pneumaquad.network.sequence import SEQUENCE_MODULUS, SequenceTracker
from pneumaquad.network.timing import accept_datagram, malformed_counts
from pneumaquad.network.wire import (
    HEADER,
    MAGIC,
    VERSION,
    Message,
    MessageType,
    ProtocolError,
    decode,
)

__all__ = ["DEFAULT_HOST", "Address", "UdpEndpoint", "parse_address"]

DEFAULT_HOST = "127.0.0.1"
Address = tuple[str, int]
_RECEIVE_BUFFER = 2048  # [B], larger than MAX_DATAGRAM: oversized datagrams are seen whole
_MAX_PEERS = 64  # trackers kept; the oldest is forgotten beyond this
_MAX_BATCH = 256  # datagrams drained per receive call
_MAX_REFUSED = 64  # refused HELLOs remembered until the owner answers them


def parse_address(text: str, default_host: str = DEFAULT_HOST) -> Address:
    """Parse ``"HOST:PORT"`` (or ``"PORT"``) into ``(host, port)``.

    Raises
    ------
    ValueError
        No valid port in 0 .. 65535.
    """
    host, _, port = text.rpartition(":")
    try:
        number = int(port)
    except ValueError:
        raise ValueError(f"{text!r}: expected HOST:PORT") from None
    if not 0 <= number <= 65535:
        raise ValueError(f"{text!r}: port outside 0 .. 65535")
    return (host or default_host, number)


class UdpEndpoint:
    """Non-blocking UDP socket speaking the protocol, with a packet log.

    Parameters
    ----------
    bind
        Local ``(host, port)``; port 0 picks a free one. 127.0.0.1 by default.
    peer
        Optional ``(host, port)``: only datagrams from there are accepted.
    joint_count
        N, for the payload-count checks of commands and ``STATE``.
    log_capacity
        Initial rows of the packet log (it grows as needed).
    busy_wait
        See :attr:`busy_wait` [s].
    hello_dimensions
        ``(joint count, control step [s])`` a received ``HELLO`` must announce (a server
        that cannot change either); ``None`` accepts any valid ``HELLO``.
    """

    def __init__(self, bind: Address = (DEFAULT_HOST, 0), peer: Address | None = None,
                 joint_count: int | None = None, log_capacity: int = 16384,
                 busy_wait: float = 0.0,
                 hello_dimensions: tuple[int, float] | None = None) -> None:
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.socket.bind(bind)
        except OSError:
            self.socket.close()
            raise
        self.socket.setblocking(False)
        self.peer = None if peer is None else (socket.gethostbyname(peer[0]), int(peer[1]))
        self.joint_count = joint_count
        self.log = PacketLog(log_capacity)
        self.trackers: dict[Address, SequenceTracker] = {}
        self.sequence = 0
        self.foreign = 0  # datagrams dropped by the peer filter [count]
        self.socket_errors = 0  # send / receive errors (e.g. ICMP port unreachable) [count]
        self.hellos: list[Address] = []  # peers whose valid HELLO reset their tracker
        self.hello_dimensions = hello_dimensions
        #: Senders of refused HELLOs and why, oldest first, until the owner takes them.
        self.refused_hellos: deque[tuple[Address, str]] = deque(maxlen=_MAX_REFUSED)
        #: Poll without sleeping for up to this long [s] before blocking in select: a reply
        #: that comes within it is picked up without a sleep/wake-up of the process (lower
        #: and steadier latency, at the cost of a busy core while waiting).
        self.busy_wait = max(0.0, float(busy_wait))

    @property
    def address(self) -> Address:
        """Bound ``(host, port)``."""
        host, port = self.socket.getsockname()[:2]
        return host, port

    def tracker(self, address: Address) -> SequenceTracker:
        """Sequence tracker of one peer (created on first use)."""
        tracker = self.trackers.get(address)
        if tracker is None:
            if len(self.trackers) >= _MAX_PEERS:
                self.trackers.pop(next(iter(self.trackers)))
            tracker = self.trackers[address] = SequenceTracker()
        return tracker

    def take_sequence(self) -> int:
        """This endpoint's next sequence number (one counter for all types)."""
        sequence = self.sequence
        self.sequence = (sequence + 1) % SEQUENCE_MODULUS
        return sequence

    def send(self, datagram: bytes, address: Address) -> bool:
        """Send and log a datagram; ``False`` (counted) when the socket refused it."""
        self.log.record_sent(datagram, time.monotonic())
        try:
            self.socket.sendto(datagram, address)
        except OSError:
            self.socket_errors += 1
            return False
        return True

    def wait(self, timeout: float) -> bool:
        """Wait up to ``timeout`` [s] until a datagram is readable (busy-polling first for
        up to :attr:`busy_wait`)."""
        if self.busy_wait > 0.0:
            deadline = time.perf_counter() + min(self.busy_wait, timeout)
            while True:
                try:
                    if select.select([self.socket], [], [], 0.0)[0]:
                        return True
                except (OSError, ValueError):
                    return False
                if time.perf_counter() >= deadline:
                    break
            timeout -= self.busy_wait
            if timeout <= 0.0:
                return False
        try:
            readable, _, _ = select.select([self.socket], [], [], max(timeout, 0.0))
        except (OSError, ValueError):
            return False
        return bool(readable)

    def receive(self, timeout: float = 0.0) -> list[tuple[Message, Address]]:
        """Accepted messages, oldest first, after waiting up to ``timeout`` [s] for one.

        Drains what is queued (at most a few hundred datagrams per call). A valid
        ``HELLO`` resets its sender's tracker before it is classified, so a restarted
        peer whose numbers start again at 0 is accepted. A ``HELLO`` with invalid
        parameters, or other than :attr:`hello_dimensions`, is dropped and logged as
        malformed (``bad_count``), and its sender appended to :attr:`refused_hellos`.
        """
        if timeout > 0.0 and not self.wait(timeout):
            return []
        accepted: list[tuple[Message, Address]] = []
        for _ in range(_MAX_BATCH):
            try:
                data, source = self.socket.recvfrom(_RECEIVE_BUFFER)
            except BlockingIOError:
                break
            except OSError:
                self.socket_errors += 1
                continue
            address = (source[0], source[1])
            if self.peer is not None and address != self.peer:
                self.foreign += 1
                continue
            now = time.monotonic()
            tracker = self.tracker(address)
            hello = self._hello(data)
            if hello is not None:
                try:
                    check_hello(hello, *(self.hello_dimensions or (None, None)))
                except ProtocolError as error:
                    self.log.record_malformed(error.reason, len(data), now)
                    self.refused_hellos.append((address, error.detail))
                    continue
                tracker.reset()
                self.hellos.append(address)
            message = accept_datagram(data, now, self.log, tracker, self.joint_count)
            if message is not None:
                accepted.append((message, address))
        return accepted

    def _hello(self, data: bytes) -> Message | None:
        """The datagram decoded when it is a well-formed ``HELLO``, else ``None``."""
        if len(data) < HEADER.size or data[:4] != MAGIC:
            return None
        _, version, kind, *_ = HEADER.unpack_from(data)
        if version != VERSION or kind != MessageType.HELLO:
            return None
        try:
            return decode(data, self.joint_count)
        except ProtocolError:
            return None

    def counters(self) -> dict[str, int]:
        """Dropped and received datagrams: malformed by reason, duplicates, reordered, ..."""
        malformed = malformed_counts(self.log)
        totals = {"received [count]": 0, "accepted [count]": 0, "duplicates [count]": 0,
                  "reordered [count]": 0, "lost [count]": 0, "resets [count]": 0}
        for tracker in self.trackers.values():
            values = tracker.counters()
            for key in totals:
                totals[key] += values[key]
        totals["received [count]"] += sum(malformed.values())
        totals["malformed [count]"] = sum(malformed.values())
        totals |= {f"malformed {reason} [count]": count for reason, count in malformed.items()}
        totals["foreign [count]"] = self.foreign
        totals["socket errors [count]"] = self.socket_errors
        return totals

    def close(self) -> None:
        """Close the socket (idempotent)."""
        self.socket.close()

    def __enter__(self) -> UdpEndpoint:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
