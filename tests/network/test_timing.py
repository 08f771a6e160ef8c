"""Packet log, timing analysis on synthetic logs with known answers, jitter, plots."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.network.packet_log import RECEIVED, SENT, Classification
from pneumaquad.network.protocol import (
    MessageType,
    SequenceTracker,
    StateMessage,
    Verdict,
    decode,
    encode_command,
    encode_ping,
    encode_pong,
    encode_state,
)
from pneumaquad.network.timing import (
    PacketLog,
    find_pauses,
    jitter_statistics,
    round_trip_times,
    sequence_statistics,
    timing_summary,
    unwrap_sequences,
)
from pneumaquad.network.timing_plots import plot_packet_timeline, plot_rtt_histogram

T = 0.001  # nominal period [s]
LOST = {10, 11, 50}  # states that never arrive
VALVE, STATE, PING, PONG = (int(MessageType.VALVE_COMMAND), int(MessageType.STATE),
                            int(MessageType.PING), int(MessageType.PONG))


def _synthetic_log() -> PacketLog:
    """Client-side log of 100 lockstep commands with known RTTs, losses and a pause.

    Command k (sequence 1000 + k) is sent at k T, +20 ms from k = 70 on (one pause); its
    STATE returns after 0.3 ms, except k = 20 (2.5 ms: after 21 and 22, reordered),
    k = 40 (1.4 ms: after 41, reordered), k in LOST (never), k = 30 (twice). Three
    pings with 0.5 ms round trips, three malformed datagrams, one state flagged late.
    The server numbers its datagrams in the order it sends them (0.1 ms after each
    request).
    """
    sends = {k: k * T + (0.02 if k >= 70 else 0.0) for k in range(100)}
    pings = {index: send for index, send in enumerate((0.0055, 0.0355, 0.1155))}
    server_order = sorted([(send + 1e-4, "state", k) for k, send in sends.items()]
                          + [(send + 1e-4, "pong", i) for i, send in pings.items()])
    server_sequence = {(kind, key): n for n, (_, kind, key) in enumerate(server_order)}
    events = []  # (time, fields for PacketLog.append)
    for k, send in sends.items():
        events.append((send, (SENT, 1000 + k, VALVE, send, math.nan, 72)))
        if k in LOST:
            continue
        rtt = {20: 0.0025, 40: T + 0.0004}.get(k, 0.0003)
        code = {20: Classification.REORDERED, 40: Classification.REORDERED,
                90: Classification.LATE}.get(k, 0)
        copies = 2 if k == 30 else 1
        for copy in range(copies):
            arrival = send + rtt + copy * 1e-5
            events.append((arrival, (RECEIVED, server_sequence["state", k], STATE, 0.0, arrival,
                                     264, Classification.DUPLICATE if copy else code,
                                     1000 + k)))
    for index, send in pings.items():
        events.append((send, (SENT, 2000 + index, PING, send, math.nan, 24)))
        events.append((send + 0.0005, (RECEIVED, server_sequence["pong", index], PONG, 0.0,
                                       send + 0.0005, 40, 0, -1, send)))
    for when, code in ((0.0101, Classification.TRUNCATED), (0.0102, Classification.TRUNCATED),
                       (0.0103, Classification.BAD_MAGIC)):
        events.append((when, (RECEIVED, -1, 0, math.nan, when, 7, code)))
    log = PacketLog(capacity=8)
    for _, fields in sorted(events, key=lambda event: event[0]):
        log.append(*fields)
    return log


def test_summary_counts_are_exact() -> None:
    summary = timing_summary(_synthetic_log(), nominal_period=T)
    assert summary["sent packets [count]"] == 103
    assert summary["received packets [count]"] == 98 + 3 + 3
    assert summary["malformed packets [count]"] == 3
    assert summary["malformed truncated [count]"] == 2
    assert summary["malformed bad_magic [count]"] == 1
    assert summary["malformed non_finite [count]"] == 0
    assert summary["lost [count]"] == 3
    assert summary["duplicated [count]"] == 1
    assert summary["reordered [count]"] == 2
    assert summary["late flagged [count]"] == 1
    assert summary["round trips [count]"] == 97 + 3
    assert summary["round trips over deadline [count]"] == 2
    assert summary["round-trip time median [s]"] == pytest.approx(0.0003)
    assert summary["round-trip time max [s]"] == pytest.approx(0.0025)
    assert summary["pauses [count]"] == 1
    assert summary["longest pause [s]"] == pytest.approx(0.021)
    assert summary["send pauses [count]"] == 1
    assert summary["pause threshold [s]"] == pytest.approx(10 * T)
    assert all(key.endswith("]") for key in summary)


def test_tracker_agrees_with_synthetic_classification() -> None:
    log = _synthetic_log()
    tracker = SequenceTracker()
    valid = (log.direction == RECEIVED) & (log.sequence >= 0)
    for sequence, code in zip(log.sequence[valid], log.classification[valid], strict=True):
        verdict = tracker.classify(int(sequence))
        expected = {Classification.DUPLICATE: Verdict.DUPLICATE,
                    Classification.REORDERED: Verdict.REORDERED}.get(int(code))
        assert (expected is None and verdict.accepted) or verdict.kind == expected
    assert (tracker.lost, tracker.duplicates, tracker.reordered) == (3, 1, 2)


def test_round_trip_sources() -> None:
    log = _synthetic_log()
    np.testing.assert_allclose(round_trip_times(log, "ping"), [0.0005] * 3)
    commands = round_trip_times(log, "command")
    assert commands.size == 97
    np.testing.assert_allclose(np.sort(commands)[-2:], [0.0014, 0.0025])
    with pytest.raises(ValueError):
        round_trip_times(log, "wireshark")
    assert round_trip_times(PacketLog()).size == 0


def test_sequence_statistics_and_wrap() -> None:
    top = 2**32 - 1
    np.testing.assert_array_equal(unwrap_sequences([top - 1, top, 0, 2, 1]),
                                  [top - 1, top, top + 1, top + 3, top + 2])
    stats = sequence_statistics(np.array([top - 1, top, 0, 2, 1, 1, 5]))
    assert stats == {"lost [count]": 2, "duplicated [count]": 1, "reordered [count]": 1}
    assert sequence_statistics(np.array([], dtype=np.int64))["lost [count]"] == 0


def test_find_pauses() -> None:
    times = np.array([0.0, 0.001, 0.002, 0.05, 0.051, 0.2])
    pauses = find_pauses(times, threshold=0.01)
    np.testing.assert_allclose(pauses, [[0.002, 0.048], [0.051, 0.149]])
    assert find_pauses(np.array([]), 0.01).shape == (0, 2)


def test_log_records_real_datagrams_and_files(tmp_path) -> None:
    log = PacketLog(capacity=1)
    command = encode_command(MessageType.TORQUE_COMMAND, 7, 0.5, np.zeros(6), 6)
    log.record_sent(command, send_time=10.0)
    zeros = np.zeros(6)
    state = encode_state(3, 99.0, StateMessage(0.5, zeros, zeros, zeros, zeros, np.zeros(3),
                                               np.array([1.0, 0, 0, 0]), 7))
    log.record_received(decode(state), len(state), 10.002)
    ping = decode(encode_ping(8, 10.1))
    log.record_sent(encode_ping(8, 10.1))
    pong = encode_pong(4, ping, 50.0, 50.0)
    log.record_received(decode(pong), len(pong), 10.1007)
    log.record_malformed("bad_version", 30, 10.2)
    assert len(log) == 5
    assert log.answered_sequence.tolist() == [-1, 7, -1, -1, -1]
    assert log.send_time[2] == 10.1 and log.echoed_time[3] == 10.1
    np.testing.assert_allclose(round_trip_times(log), [0.0007, 0.002])
    for suffix in ("parquet", "csv"):
        path = log.write(tmp_path / f"packets.{suffix}")
        back = PacketLog.read(path)
        for name, values in log.columns().items():
            np.testing.assert_array_equal(back.columns()[name], values, err_msg=name)
    assert "receive time [s]" in log.to_table().column_names
    assert log.to_table()["classification [-]"].to_pylist()[-1] == "BAD_VERSION"
    with pytest.raises(ValueError):
        log.write(tmp_path / "packets.txt")


def test_plots_are_written(tmp_path) -> None:
    log = _synthetic_log()
    assert plot_rtt_histogram(log, tmp_path / "rtt.png", deadline=T).stat().st_size > 0
    assert plot_packet_timeline(log, T, tmp_path / "timeline.png").stat().st_size > 0
    assert plot_rtt_histogram(PacketLog(), tmp_path / "empty.png").exists()


def test_jitter_statistics_known_schedule() -> None:
    times = np.arange(1000) * T
    times[500] += 0.0003  # one late wake-up
    times = np.delete(times, [800, 801])  # one overrun: two slots missed
    stats = jitter_statistics(times, T)
    assert stats["wake-ups [count]"] == 998
    assert stats["nominal rate [Hz]"] == pytest.approx(1000.0)
    assert stats["achieved rate [Hz]"] == pytest.approx(997 / 0.999)
    assert stats["jitter p50 [s]"] == pytest.approx(0.0, abs=1e-12)
    assert stats["jitter max [s]"] == pytest.approx(2 * T)
    assert stats["max lateness [s]"] == pytest.approx(2 * T)
    assert stats["overruns [count]"] == 1
    assert jitter_statistics(times, T, overrun_tolerance=0.25)["overruns [count]"] == 2
    assert math.isnan(jitter_statistics(np.array([1.0]), T)["jitter max [s]"])
    with pytest.raises(ValueError):
        jitter_statistics(times, 0.0)
