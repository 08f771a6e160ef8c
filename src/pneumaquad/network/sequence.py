"""Sequence numbers: serial-number arithmetic and per-peer tracking.

Sequence numbers are unsigned 32-bit and wrap from 2**32 - 1 to 0. Which of two numbers
is newer follows serial-number arithmetic (RFC 1982, SERIAL_BITS = 32): ``a`` is newer
than ``b`` when ``(a - b) mod 2**32`` lies in ``1 .. 2**31 - 1``. A difference of
exactly 2**31 is undefined in the RFC; here it counts as older (the packet is dropped).

A receiver keeps one :class:`SequenceTracker` per peer and drops everything that is not
newer than the newest accepted packet (duplicates and reordered packets): a stale command
or state must never overwrite a newer one.
"""

from __future__ import annotations

from enum import IntEnum
from typing import NamedTuple

SEQUENCE_MODULUS = 2**32
_HALF = 2**31
WINDOW = 1024  # number of recent sequence numbers remembered for duplicate detection


def serial_difference(newer: int, older: int) -> int:
    """Signed distance ``newer - older`` in serial-number arithmetic.

    Parameters
    ----------
    newer, older
        Sequence numbers, 0 .. 2**32 - 1.

    Returns
    -------
    int
        In ``-2**31 .. 2**31 - 1``; positive when ``newer`` is newer than ``older``.
        A raw difference of exactly 2**31 maps to ``-2**31`` (older).
    """
    difference = (newer - older) % SEQUENCE_MODULUS
    return difference - SEQUENCE_MODULUS if difference >= _HALF else difference


class Verdict(IntEnum):
    """Classification of one received sequence number."""

    NEW = 0  # exactly one newer than the newest seen (or the first packet)
    GAP = 1  # newer, with ``missing`` numbers skipped in between
    DUPLICATE = 2  # seen before (within the last WINDOW numbers)
    REORDERED = 3  # older than the newest seen and not seen before


class SequenceVerdict(NamedTuple):
    """Verdict on one sequence number and how many numbers it skipped (``GAP`` only)."""

    kind: Verdict
    missing: int = 0

    @property
    def accepted(self) -> bool:
        """Whether a receiver should act on the packet (``NEW`` or ``GAP``)."""
        return self.kind in (Verdict.NEW, Verdict.GAP)


class SequenceTracker:
    """Classify the sequence numbers received from one peer.

    Counters (cumulative, kept across :meth:`reset` unless asked otherwise):
    ``received``, ``new`` (accepted, gaps included), ``gaps`` (gap events),
    ``missing`` (numbers skipped by gaps), ``recovered`` (skipped numbers that arrived
    later), ``duplicates``, ``reordered``, ``resets``; :attr:`lost` = missing - recovered.

    Parameters
    ----------
    window
        How many recent numbers are remembered to tell a duplicate from a late
        arrival; an older number is counted as reordered.
    """

    def __init__(self, window: int = WINDOW) -> None:
        if window < 1:
            raise ValueError("window must be >= 1")
        self.window = window
        self._mask_all = (1 << window) - 1
        self.newest: int | None = None
        self._seen = 0  # bit k set: newest - k was received
        self._skipped = 0  # bit k set: newest - k was skipped by a gap and not yet received
        self.received = self.new = self.gaps = self.missing = self.recovered = 0
        self.duplicates = self.reordered = self.resets = 0

    @property
    def lost(self) -> int:
        """Numbers skipped by gaps that have not arrived (so far) [count]."""
        return self.missing - self.recovered

    def classify(self, sequence: int) -> SequenceVerdict:
        """Record one received sequence number and classify it.

        Parameters
        ----------
        sequence
            Sequence number from the datagram header, 0 .. 2**32 - 1.

        Returns
        -------
        SequenceVerdict
            ``NEW``/``GAP`` (accept; ``missing`` numbers skipped) or ``DUPLICATE``/
            ``REORDERED`` (drop).
        """
        if not 0 <= sequence < SEQUENCE_MODULUS:
            raise ValueError(f"sequence number {sequence} outside 0 .. 2**32 - 1")
        self.received += 1
        if self.newest is None:
            self._advance(sequence, 0, 0)
            return SequenceVerdict(Verdict.NEW)
        distance = serial_difference(sequence, self.newest)
        if distance > 0:
            missing = distance - 1
            self._advance(sequence, distance, missing)
            if missing:
                self.gaps += 1
                self.missing += missing
                return SequenceVerdict(Verdict.GAP, missing)
            return SequenceVerdict(Verdict.NEW)
        age = -distance
        if age < self.window:
            bit = 1 << age
            if self._seen & bit:
                self.duplicates += 1
                return SequenceVerdict(Verdict.DUPLICATE)
            self._seen |= bit
            if self._skipped & bit:
                self._skipped &= ~bit
                self.recovered += 1
        self.reordered += 1
        return SequenceVerdict(Verdict.REORDERED)

    def _advance(self, sequence: int, distance: int, missing: int) -> None:
        self.new += 1
        self.newest = sequence
        # Bits 1 .. missing stand for the numbers between the old and the new newest.
        skipped_bits = (((1 << min(missing, self.window)) - 1) << 1) & self._mask_all
        if distance >= self.window:
            self._seen, self._skipped = 1, skipped_bits
            return
        self._seen = ((self._seen << distance) | 1) & self._mask_all
        self._skipped = ((self._skipped << distance) | skipped_bits) & self._mask_all

    def reset(self, clear_counters: bool = False) -> None:
        """Forget the newest number (resynchronisation): the next packet is ``NEW``.

        Parameters
        ----------
        clear_counters
            Also zero the counters (``resets`` included).
        """
        self.newest = None
        self._seen = self._skipped = 0
        if clear_counters:
            self.received = self.new = self.gaps = self.missing = self.recovered = 0
            self.duplicates = self.reordered = self.resets = 0
        else:
            self.resets += 1

    def counters(self) -> dict[str, int]:
        """Return the counters as a dict ``{"received [count]": ..., ...}``."""
        return {
            "received [count]": self.received, "accepted [count]": self.new,
            "gaps [count]": self.gaps, "missing [count]": self.missing,
            "recovered [count]": self.recovered, "lost [count]": self.lost,
            "duplicates [count]": self.duplicates, "reordered [count]": self.reordered,
            "resets [count]": self.resets,
        }
