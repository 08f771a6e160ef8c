"""A fault-injecting UDP relay between a client and a server, for tests.

The thesis's link suffered pauses of up to 100 ms and lost packets (Daepp 2011,
ch. 5.3.1-5.3.2). :class:`FaultProxy` reproduces such a link on the loopback: the client
sends to the proxy, which forwards to the server from its own socket and relays the
replies back to the last client. Per datagram and direction, with a seeded RNG, it
drops, delays (uniform in ``delay_range``), duplicates (the copy right after the
original), reorders (holds it until the next forwarded datagram has gone) or forwards it,
and before some forwarded datagrams it injects a garbage datagram (always malformed:
truncated, bad magic, bad version or a NaN payload). Only commands (client -> server)
and ``STATE`` (server -> client) are faulted; ``HELLO``, ``PING``, ``PONG`` and ``BYE``
pass untouched. :attr:`FaultProxy.counts` says what it did, per direction.
"""

from __future__ import annotations

import heapq
import random
import select
import socket
import struct
import threading
import time
from dataclasses import dataclass, field

from pneumaquad.network.endpoint import DEFAULT_HOST, Address

__all__ = ["FaultCounts", "FaultProxy", "FaultRates"]

_HEADER = struct.Struct("<4sHHIdHH")
_FAULTED_TYPES = {"to_server": (1, 2, 3), "to_client": (4,)}


@dataclass(frozen=True)
class FaultRates:
    """Probabilities per faulted datagram (drop, delay, duplicate, reorder exclusive)."""

    drop: float = 0.10
    delay: float = 0.03
    duplicate: float = 0.03
    reorder: float = 0.03
    garbage: float = 0.03
    delay_range: tuple[float, float] = (0.05, 0.10)  # [s]


@dataclass
class FaultCounts:
    """What the proxy did in one direction [count]."""

    forwarded: int = 0
    dropped: int = 0
    delayed: int = 0
    duplicated: int = 0
    reordered: int = 0
    garbage: int = 0
    passed: int = 0  # unfaulted types
    kinds: dict[str, int] = field(default_factory=dict)


class FaultProxy:
    """UDP relay with seeded faults; run it in a thread with :meth:`start`.

    Parameters
    ----------
    server
        Server ``(host, port)``.
    rates
        Fault probabilities.
    seed
        RNG seed (reproducible decisions for a given datagram order).
    bind
        Address the client sends to; 127.0.0.1 and a free port by default.
    """

    def __init__(self, server: Address, rates: FaultRates = FaultRates(), seed: int = 0,
                 bind: Address = (DEFAULT_HOST, 0)) -> None:
        self.server = server
        self.rates = rates
        self.random = random.Random(seed)
        self.front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.front.bind(bind)
        self.back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.back.bind((DEFAULT_HOST, 0))
        self.client: Address | None = None
        self.counts = {"to_server": FaultCounts(), "to_client": FaultCounts()}
        self.enabled = True
        self._held: dict[str, bytes | None] = {"to_server": None, "to_client": None}
        self._delayed: list[tuple[float, int, str, bytes]] = []
        self._order = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def address(self) -> Address:
        """Where the client sends."""
        host, port = self.front.getsockname()[:2]
        return host, port

    def start(self) -> FaultProxy:
        """Relay in a daemon thread."""
        self._thread = threading.Thread(target=self._run, name="fault-proxy", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the relay and close its sockets."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
        self.front.close()
        self.back.close()

    def _send(self, direction: str, data: bytes) -> None:
        try:
            if direction == "to_server":
                self.back.sendto(data, self.server)
            elif self.client is not None:
                self.front.sendto(data, self.client)
        except OSError:
            pass

    def _garbage(self, counts: FaultCounts) -> bytes:
        kind = self.random.choice(("truncated", "bad_magic", "bad_version", "non_finite"))
        counts.kinds[kind] = counts.kinds.get(kind, 0) + 1
        if kind == "truncated":
            return bytes(self.random.getrandbits(8) for _ in range(self.random.randrange(24)))
        if kind == "bad_magic":
            return _HEADER.pack(b"XXXX", 1, 2, 7, 0.0, 0, 0)
        if kind == "bad_version":
            return _HEADER.pack(b"PNQD", 9, 2, 7, 0.0, 0, 0)
        return _HEADER.pack(b"PNQD", 1, 5, 7, float("nan"), 0, 0)  # PING with NaN time

    def _relay(self, direction: str, data: bytes) -> None:
        counts = self.counts[direction]
        kind = _HEADER.unpack_from(data)[2] if len(data) >= _HEADER.size else 0
        if not self.enabled or kind not in _FAULTED_TYPES[direction]:
            counts.passed += 1
            self._send(direction, data)
            return
        rates, draw = self.rates, self.random.random()
        if draw < rates.drop:
            counts.dropped += 1
            return
        draw -= rates.drop
        if draw < rates.delay:
            counts.delayed += 1
            due = time.monotonic() + self.random.uniform(*rates.delay_range)
            self._order += 1
            heapq.heappush(self._delayed, (due, self._order, direction, data))
            return
        draw -= rates.delay
        if draw < rates.reorder and self._held[direction] is None:
            counts.reordered += 1
            self._held[direction] = data
            return
        if self.random.random() < rates.garbage:
            counts.garbage += 1
            self._send(direction, self._garbage(counts))
        counts.forwarded += 1
        self._send(direction, data)
        if draw - rates.reorder < rates.duplicate and draw >= rates.reorder:
            counts.duplicated += 1
            self._send(direction, data)
        held, self._held[direction] = self._held[direction], None
        if held is not None:
            self._send(direction, held)

    def _run(self) -> None:
        sockets = [self.front, self.back]
        while not self._stop.is_set():
            wait = 0.02
            if self._delayed:
                wait = min(wait, max(self._delayed[0][0] - time.monotonic(), 0.0))
            try:
                readable, _, _ = select.select(sockets, [], [], wait)
            except (OSError, ValueError):
                return
            for sock in readable:
                try:
                    data, source = sock.recvfrom(2048)
                except OSError:
                    continue
                if sock is self.front:
                    self.client = (source[0], source[1])
                    self._relay("to_server", data)
                else:
                    self._relay("to_client", data)
            while self._delayed and self._delayed[0][0] <= time.monotonic():
                _, _, direction, data = heapq.heappop(self._delayed)
                self._send(direction, data)
