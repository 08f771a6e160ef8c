"""Splitting a step train into steps, and per-step figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumaquad.analysis.segmentation import StepSegment, find_steps, metrics_per_step

DT = 1e-3
LEVELS = [0.01, 0.02, 0.035, 0.005, 0.02]  # m, a closed-loop reference step train
DWELL = 600  # samples per level
TIME = np.arange(len(LEVELS) * DWELL) * DT
COMMAND = np.repeat(LEVELS, DWELL)
CHANGE_INDICES = [600, 1200, 1800, 2400]


def test_exact_change_instants_and_levels():
    segments = find_steps(TIME, COMMAND, threshold=1e-3)
    assert [s.start_index for s in segments] == CHANGE_INDICES
    assert [s.end_index for s in segments] == [*CHANGE_INDICES[1:], COMMAND.size]
    assert [s.start_time for s in segments] == pytest.approx([0.6, 1.2, 1.8, 2.4])
    assert [s.end_time for s in segments] == pytest.approx([1.199, 1.799, 2.399, 2.999])
    assert [s.initial_level for s in segments] == LEVELS[:-1]
    assert [s.final_level for s in segments] == LEVELS[1:]
    assert segments[2].step_size == pytest.approx(-0.03)
    assert isinstance(segments[0], StepSegment)


def test_noise_below_threshold_and_multi_sample_transitions():
    rng = np.random.default_rng(2)
    noisy = COMMAND + rng.uniform(-2e-4, 2e-4, COMMAND.size)
    # The third change spreads over three samples (a slewed command).
    noisy[1800:1802] = [0.025, 0.015]
    segments = find_steps(TIME, noisy, threshold=2e-3)
    assert [s.start_index for s in segments] == CHANGE_INDICES
    assert [s.final_level for s in segments] == pytest.approx(LEVELS[1:], abs=2e-4)
    assert [s.initial_level for s in segments] == pytest.approx(LEVELS[:-1], abs=2e-4)


def test_threshold_above_every_step_finds_nothing_and_bad_input_is_rejected():
    assert find_steps(TIME, COMMAND, threshold=0.05) == []
    assert find_steps(TIME[:10], np.full(10, 3.0), threshold=0.1) == []
    with pytest.raises(ValueError, match="threshold"):
        find_steps(TIME, COMMAND, threshold=0.0)
    with pytest.raises(ValueError, match="samples"):
        find_steps(TIME[:-1], COMMAND, threshold=1e-3)
    with pytest.raises(ValueError, match="NaN"):
        find_steps(TIME, np.where(TIME > 1, np.nan, 0.0), threshold=1e-3)


def first_order_follower(command: np.ndarray, tau: float) -> np.ndarray:
    """Exact sampled response of a first-order lag to a piecewise-constant input."""
    decay = math.exp(-DT / tau)
    output = np.empty_like(command)
    output[0] = command[0]
    for k in range(1, command.size):
        # Input held over [t_{k-1}, t_k) at command[k]: the new level acts from sample k on.
        output[k] = command[k] + (output[k - 1] - command[k]) * decay
    return output


def test_metrics_per_step_of_a_first_order_follower():
    tau = 0.05  # s
    response = first_order_follower(COMMAND, tau)
    table = metrics_per_step(TIME, response, COMMAND, threshold=1e-3, unit="m")
    assert [row["step"] for row in table] == [1, 2, 3, 4]
    assert [row["start time [s]"] for row in table] == pytest.approx([0.6, 1.2, 1.8, 2.4])
    assert [row["final command"] for row in table] == LEVELS[1:]
    for row in table:
        # The response is the lag delayed by one sample (the input acts from the change on).
        assert row["rise time [s]"] == pytest.approx(tau * math.log(9), abs=1e-4)
        assert row["settling time [s]"] == pytest.approx(tau * math.log(50) + DT, abs=2 * DT)
        assert row["overshoot [%]"] == 0.0
        assert abs(row["steady-state error [m]"]) < 1e-6
        assert row["final level [m]"] == row["final command"]


def test_metrics_per_step_with_levels_from_the_response():
    # Open loop: a valve command in V drives a pressure in Pa with its own levels.
    command = np.repeat([2.0, 8.0, 3.0], 500)
    time = np.arange(command.size) * DT
    pressure = first_order_follower(1.0e5 + 5.0e4 * command, 0.03)
    table = metrics_per_step(
        time, pressure, command, threshold=0.5, levels_from="response", unit="Pa"
    )
    assert len(table) == 2
    assert table[0]["final level [Pa]"] == pytest.approx(5.0e5, rel=1e-4)
    assert table[1]["final level [Pa]"] == pytest.approx(2.5e5, rel=1e-4)
    assert "steady-state error [Pa]" not in table[0]
    assert table[0]["rise time [s]"] == pytest.approx(0.03 * math.log(9), rel=0.02)
    with pytest.raises(ValueError, match="levels_from"):
        metrics_per_step(time, pressure, command, 0.5, levels_from="both")
