"""Sequence tracking: duplicates, reorders, gaps, wrap-around, resynchronisation."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pneumaquad.network.sequence import SequenceTracker, Verdict, serial_difference

TOP = 2**32 - 1


def _kinds(tracker: SequenceTracker, numbers: list[int]) -> list[tuple[Verdict, int]]:
    return [tuple(tracker.classify(n)) for n in numbers]


def test_serial_difference_wraps() -> None:
    assert serial_difference(0, TOP) == 1
    assert serial_difference(TOP, 0) == -1
    assert serial_difference(5, 3) == 2
    assert serial_difference(2**31, 0) == -(2**31)  # undefined in RFC 1982: treated as older
    assert serial_difference(2**31 - 1, 0) == 2**31 - 1


def test_in_order_stream_is_all_new() -> None:
    tracker = SequenceTracker()
    assert all(kind == Verdict.NEW for kind, _ in _kinds(tracker, list(range(100))))
    assert (tracker.new, tracker.lost, tracker.duplicates, tracker.reordered) == (100, 0, 0, 0)


def test_duplicates_reorders_and_gaps() -> None:
    tracker = SequenceTracker()
    verdicts = _kinds(tracker, [0, 1, 1, 4, 3, 3, 0, 2, 7, 5])
    assert verdicts == [
        (Verdict.NEW, 0), (Verdict.NEW, 0), (Verdict.DUPLICATE, 0), (Verdict.GAP, 2),
        (Verdict.REORDERED, 0), (Verdict.DUPLICATE, 0), (Verdict.DUPLICATE, 0),
        (Verdict.REORDERED, 0), (Verdict.GAP, 2), (Verdict.REORDERED, 0)]
    assert tracker.received == 10
    assert tracker.new == 4  # 0, 1, 4, 7
    assert (tracker.gaps, tracker.missing, tracker.recovered) == (2, 4, 3)
    assert tracker.lost == 1  # 6 never arrived
    assert (tracker.duplicates, tracker.reordered) == (3, 3)
    assert tracker.counters()["lost [count]"] == 1
    assert tracker.classify(8).accepted and not tracker.classify(6).accepted
    assert tracker.lost == 0


def test_wrap_around() -> None:
    tracker = SequenceTracker()
    verdicts = _kinds(tracker, [TOP - 2, TOP - 1, TOP, 0, 1, 3, TOP, 2])
    assert [kind for kind, _ in verdicts] == [
        Verdict.NEW, Verdict.NEW, Verdict.NEW, Verdict.NEW, Verdict.NEW, Verdict.GAP,
        Verdict.DUPLICATE, Verdict.REORDERED]
    assert verdicts[5] == (Verdict.GAP, 1)
    assert tracker.newest == 3 and tracker.lost == 0


def test_gap_across_wrap_and_far_old_packets() -> None:
    tracker = SequenceTracker(window=16)
    assert tuple(tracker.classify(TOP - 1)) == (Verdict.NEW, 0)
    assert tuple(tracker.classify(10)) == (Verdict.GAP, 11)  # TOP, 0..9 skipped
    assert tracker.classify(TOP).kind == Verdict.REORDERED
    assert tracker.recovered == 1
    tracker.classify(1000)  # jump far beyond the window
    assert tracker.classify(10).kind == Verdict.REORDERED  # too old to tell: not a duplicate
    assert tracker.classify(999).kind == Verdict.REORDERED  # skipped, inside the window
    assert tracker.lost == 10 + 989 - 1


def test_half_range_jump_counts_as_old() -> None:
    tracker = SequenceTracker()
    tracker.classify(0)
    assert tracker.classify(2**31).kind == Verdict.REORDERED
    assert tracker.classify(2**31 - 1) == (Verdict.GAP, 2**31 - 2)


def test_reset_resynchronises() -> None:
    tracker = SequenceTracker()
    _kinds(tracker, [100, 101, 102])
    assert tracker.classify(0).kind == Verdict.REORDERED
    tracker.reset()
    assert tracker.classify(0).kind == Verdict.NEW
    assert tracker.classify(1).kind == Verdict.NEW
    assert tracker.resets == 1 and tracker.received == 6
    tracker.reset(clear_counters=True)
    assert tracker.received == 0 and tracker.resets == 0 and tracker.newest is None
    with pytest.raises(ValueError):
        tracker.classify(-1)
    with pytest.raises(ValueError):
        SequenceTracker(window=0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.permutations(list(range(40))),
       st.lists(st.integers(0, 39), max_size=10))
def test_any_arrival_order_accounts_for_every_packet(start, order, repeats):
    tracker = SequenceTracker()
    numbers = [(start + k) % 2**32 for k in order + repeats]
    kinds = [tracker.classify(n).kind for n in numbers]
    assert kinds.count(Verdict.DUPLICATE) == len(repeats)
    assert tracker.new + tracker.reordered + tracker.duplicates == len(numbers)
    # Every number arrives (within the window), so every skipped one is recovered;
    # numbers below the first arrival count as reordered, never as missing.
    assert tracker.lost == 0 and tracker.missing == tracker.recovered
    assert tracker.newest == (start + max(order)) % 2**32
    assert tracker.reordered == sum(
        1 for i, k in enumerate(order) if i and k < max(order[:i]))
