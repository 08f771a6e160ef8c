"""Packet-timing analysis of a co-simulation link (replaces the thesis's Wireshark work).

The thesis found its co-simulation "clouded with high frequency oscillations" caused by
pauses of up to 100 ms in the UDP exchange, located them by timestamping packets and
matching pauses to Wireshark captures (Daepp 2011, ch. 5.3.1-5.3.2, Fig. 37), and
reported 3-4 ms of total travel time after the fix. The functions here compute the same
quantities from a :class:`~pneumaquad.network.packet_log.PacketLog`: round-trip times,
inter-arrival gaps and pauses, lost / duplicated / reordered / late / malformed counts,
plus the wake-up jitter of a paced loop. Plots are in
:mod:`pneumaquad.network.timing_plots`.
"""

from __future__ import annotations

import math

import numpy as np

from pneumaquad.network.packet_log import (
    MALFORMED_CODES,
    MALFORMED_MIN,
    RECEIVED,
    SENT,
    Classification,
    PacketLog,
)
from pneumaquad.network.sequence import SEQUENCE_MODULUS, SequenceTracker, Verdict
from pneumaquad.network.wire import COMMAND_TYPES, Message, MessageType, ProtocolError, decode

__all__ = [
    "PacketLog", "accept_datagram", "find_pauses", "inter_arrival_gaps", "jitter_statistics",
    "malformed_counts", "round_trip_times", "rtt_statistics", "sequence_statistics",
    "timing_summary", "unwrap_sequences",
]

_VERDICT_CODES = {Verdict.NEW: Classification.OK, Verdict.GAP: Classification.OK,
                  Verdict.DUPLICATE: Classification.DUPLICATE,
                  Verdict.REORDERED: Classification.REORDERED}


def accept_datagram(datagram: bytes, receive_time: float, log: PacketLog,
                    tracker: SequenceTracker, joint_count: int | None = None) -> Message | None:
    """Receiver policy in one call: decode, classify, log; return what to act on.

    Parameters
    ----------
    datagram
        Bytes as received.
    receive_time
        Local monotonic clock at reception [s].
    log
        Packet log to append to.
    tracker
        Sequence tracker of the sending peer.
    joint_count
        Expected joint count, passed to :func:`~pneumaquad.network.wire.decode`.

    Returns
    -------
    Message or None
        The message when it is valid and newer than anything accepted before; ``None``
        for malformed, duplicate and reordered datagrams (dropped and counted).
    """
    try:
        message = decode(datagram, joint_count)
    except ProtocolError as error:
        log.record_malformed(error.reason, len(datagram), receive_time)
        return None
    verdict = tracker.classify(message.sequence)
    log.record_received(message, len(datagram), receive_time, _VERDICT_CODES[verdict.kind])
    return message if verdict.accepted else None


def unwrap_sequences(sequences: np.ndarray) -> np.ndarray:
    """Unwrap 32-bit sequence numbers (in arrival order) onto a continuous int64 axis.

    Consecutive numbers are joined by their serial-number difference (RFC 1982), so a
    wrap from 2**32 - 1 to 0 continues at 2**32.
    """
    sequences = np.asarray(sequences, dtype=np.int64)
    if sequences.size == 0:
        return sequences.copy()
    steps = np.diff(sequences) % SEQUENCE_MODULUS
    steps = np.where(steps >= SEQUENCE_MODULUS // 2, steps - SEQUENCE_MODULUS, steps)
    return sequences[0] + np.concatenate(([0], np.cumsum(steps)))


def sequence_statistics(sequences: np.ndarray) -> dict[str, int]:
    """Lost, duplicated and reordered packets of one sender's stream.

    Parameters
    ----------
    sequences
        Sequence numbers of the valid received packets, in arrival order.

    Returns
    -------
    dict
        ``"lost [count]"``: numbers between the lowest and highest received that never
        arrived (a gap filled later is not lost; losses after the last arrival cannot be
        seen); ``"duplicated [count]"``: extra copies; ``"reordered [count]"``: first
        copies that arrived after a higher number.
    """
    unwrapped = unwrap_sequences(sequences)
    if unwrapped.size == 0:
        return {"lost [count]": 0, "duplicated [count]": 0, "reordered [count]": 0}
    unique, first = np.unique(unwrapped, return_index=True)
    span = int(unique[-1] - unique[0] + 1)
    previous_max = np.concatenate(([np.iinfo(np.int64).min], np.maximum.accumulate(unwrapped)[:-1]))
    reordered = int(np.count_nonzero(unwrapped[first] < previous_max[first]))
    return {"lost [count]": span - unique.size,
            "duplicated [count]": int(unwrapped.size - unique.size),
            "reordered [count]": reordered}


def round_trip_times(log: PacketLog, source: str = "all") -> np.ndarray:
    """Round-trip times measured by this peer [s].

    Parameters
    ----------
    log
        Packet log of the peer that sent the pings / commands.
    source
        ``"ping"``: ``PONG`` receive time minus the echoed ping time (both this peer's
        monotonic clock); ``"command"``: receive time of the first ``STATE`` answering a
        command minus that command's logged send time; ``"all"``: both, concatenated.

    Returns
    -------
    numpy.ndarray
        Round-trip times [s] (duplicates and malformed packets excluded).
    """
    if source not in ("all", "ping", "command"):
        raise ValueError(f"unknown round-trip source {source!r}")
    received = ((log.direction == RECEIVED) & (log.classification < MALFORMED_MIN)
                & (log.classification != Classification.DUPLICATE))
    parts = []
    if source in ("all", "ping"):
        pongs = received & (log.message_type == MessageType.PONG)
        parts.append(log.receive_time[pongs] - log.echoed_time[pongs])
    if source in ("all", "command"):
        sent = (log.direction == SENT) & np.isin(log.message_type, [int(t) for t in COMMAND_TYPES])
        states = received & (log.message_type == MessageType.STATE) & (log.answered_sequence >= 0)
        answered, first = np.unique(log.answered_sequence[states], return_index=True)
        receive = log.receive_time[states][first]
        # Latest send of each sequence number (one per number in logs < 2**32 packets).
        keys, last = np.unique(log.sequence[sent][::-1], return_index=True)
        times = log.send_time[sent][::-1][last]
        index = np.minimum(np.searchsorted(keys, answered), keys.size - 1)
        matched = (keys[index] == answered) if keys.size else np.zeros(answered.size, bool)
        parts.append((receive - times[index])[matched] if keys.size else np.empty(0))
    return np.concatenate(parts) if parts else np.empty(0)


def rtt_statistics(rtts: np.ndarray) -> dict[str, float]:
    """Count, median, p90, p99 and max of round-trip times [s] (NaN when empty)."""
    rtts = np.asarray(rtts, dtype=float)
    if rtts.size == 0:
        return {"round trips [count]": 0, "round-trip time median [s]": math.nan,
                "round-trip time p90 [s]": math.nan, "round-trip time p99 [s]": math.nan,
                "round-trip time max [s]": math.nan}
    p50, p90, p99 = np.percentile(rtts, [50, 90, 99])
    return {"round trips [count]": int(rtts.size), "round-trip time median [s]": float(p50),
            "round-trip time p90 [s]": float(p90), "round-trip time p99 [s]": float(p99),
            "round-trip time max [s]": float(rtts.max())}


def inter_arrival_gaps(times: np.ndarray) -> np.ndarray:
    """Differences between consecutive (sorted) event times [s]."""
    return np.diff(np.sort(np.asarray(times, dtype=float)))


def find_pauses(times: np.ndarray, threshold: float) -> np.ndarray:
    """Pauses: silences longer than ``threshold`` between consecutive events.

    Parameters
    ----------
    times
        Event times [s], e.g. receive times.
    threshold
        Shortest gap counted as a pause [s], e.g. 10 nominal periods.

    Returns
    -------
    numpy.ndarray
        Shape (k, 2): start (time of the last event before the pause) [s] and
        duration [s] of each pause.
    """
    times = np.sort(np.asarray(times, dtype=float))
    gaps = np.diff(times)
    long = gaps > threshold
    return np.column_stack((times[:-1][long], gaps[long])) if times.size else np.empty((0, 2))


def malformed_counts(log: PacketLog) -> dict[str, int]:
    """Malformed received datagrams by ``ProtocolError`` reason [count]."""
    codes = log.classification[log.direction == RECEIVED]
    return {reason: int(np.count_nonzero(codes == code))
            for reason, code in MALFORMED_CODES.items()}


def timing_summary(log: PacketLog, nominal_period: float, deadline: float | None = None,
                   pause_factor: float = 10.0) -> dict[str, float | int]:
    """Figures of merit of one peer's link, keyed ``"quantity [unit]"``.

    Parameters
    ----------
    log
        This peer's packet log.
    nominal_period
        Nominal exchange period [s] (the control step).
    deadline
        Round trips longer than this are late [s]; defaults to ``nominal_period``.
    pause_factor
        A gap longer than ``pause_factor * nominal_period`` is a pause.

    Returns
    -------
    dict
        Packet counts, lost / duplicated / reordered / late / malformed counts,
        round-trip statistics, inter-arrival statistics, pauses and rates; NaN where a
        quantity has no data.
    """
    deadline = nominal_period if deadline is None else deadline
    threshold = pause_factor * nominal_period
    received = log.direction == RECEIVED
    valid = received & (log.classification < MALFORMED_MIN)
    sent = log.direction == SENT
    arrivals = log.receive_time[valid]
    sends = log.send_time[sent]
    gaps = inter_arrival_gaps(arrivals)
    pauses = find_pauses(arrivals, threshold)
    rtts = round_trip_times(log)
    malformed = malformed_counts(log)
    summary: dict[str, float | int] = {
        "nominal period [s]": float(nominal_period), "deadline [s]": float(deadline),
        "pause threshold [s]": float(threshold),
        "sent packets [count]": int(np.count_nonzero(sent)),
        "received packets [count]": int(np.count_nonzero(received)),
        "malformed packets [count]": int(sum(malformed.values())),
    }
    summary |= {f"malformed {reason} [count]": count for reason, count in malformed.items()}
    summary |= sequence_statistics(log.sequence[valid])
    summary["late flagged [count]"] = int(np.count_nonzero(
        received & (log.classification == Classification.LATE)))
    summary["round trips over deadline [count]"] = int(np.count_nonzero(rtts > deadline))
    summary |= rtt_statistics(rtts)
    summary |= {
        "inter-arrival median [s]": float(np.median(gaps)) if gaps.size else math.nan,
        "inter-arrival p99 [s]": float(np.percentile(gaps, 99)) if gaps.size else math.nan,
        "inter-arrival max [s]": float(gaps.max()) if gaps.size else math.nan,
        "pauses [count]": int(pauses.shape[0]),
        "longest pause [s]": float(pauses[:, 1].max()) if pauses.size else math.nan,
        "send pauses [count]": int(find_pauses(sends, threshold).shape[0]),
        "receive rate [Hz]": _rate(arrivals), "send rate [Hz]": _rate(sends),
    }
    return summary


def _rate(times: np.ndarray) -> float:
    times = times[np.isfinite(times)]
    span = float(times.max() - times.min()) if times.size > 1 else 0.0
    return (times.size - 1) / span if span > 0 else math.nan


def jitter_statistics(wakeup_times: np.ndarray, period: float,
                      overrun_tolerance: float = 0.5) -> dict[str, float | int]:
    """Real-time quality of a paced loop from its wake-up times.

    Parameters
    ----------
    wakeup_times
        Monotonic times at which the loop woke up, one per cycle [s].
    period
        Nominal period [s].
    overrun_tolerance
        An interval longer than ``(1 + overrun_tolerance) * period`` is an overrun.

    Returns
    -------
    dict
        ``"wake-ups [count]"``, ``"nominal rate [Hz]"``, ``"achieved rate [Hz]"``
        (intervals / time span), ``"jitter p50 [s]"``, ``"jitter p99 [s]"``,
        ``"jitter max [s]"`` (of ``|interval - period|``), ``"max lateness [s]"``
        (largest ``t_k - (t_0 + k period)``, drift included) and ``"overruns [count]"``.
    """
    if not period > 0:
        raise ValueError("period must be > 0")
    times = np.asarray(wakeup_times, dtype=float)
    intervals = np.diff(times)
    error = np.abs(intervals - period)
    span = float(times[-1] - times[0]) if times.size > 1 else 0.0
    lateness = times - (times[0] + period * np.arange(times.size)) if times.size else times
    has = intervals.size > 0
    return {
        "wake-ups [count]": int(times.size),
        "nominal rate [Hz]": 1.0 / period,
        "achieved rate [Hz]": intervals.size / span if span > 0 else math.nan,
        "jitter p50 [s]": float(np.percentile(error, 50)) if has else math.nan,
        "jitter p99 [s]": float(np.percentile(error, 99)) if has else math.nan,
        "jitter max [s]": float(error.max()) if has else math.nan,
        "max lateness [s]": float(lateness.max()) if times.size else math.nan,
        "overruns [count]": int(np.count_nonzero(intervals > (1 + overrun_tolerance) * period)),
    }
