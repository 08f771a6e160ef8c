"""The online crawl: stable shifts, one leg at a time, footholds, refusals, shared control."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.gait.crawl import LEGS
from pneumaquad.gait.online import (
    RETRY_MARGIN,
    OnlineCrawl,
    OnlineCrawlSettings,
    shift_for_margin,
    swing_point,
)
from pneumaquad.gait.stability import stability_margin, support_polygon

NEUTRAL = np.array([[0.3, 0.25, -0.35], [0.3, -0.25, -0.35],
                    [-0.3, 0.25, -0.35], [-0.3, -0.25, -0.35]])
STEP = 0.02  # [s]


def _run(crawl: OnlineCrawl, duration: float, allowed: bool = True) -> list[float]:
    """Advance; return the planned margin at every lift-off."""
    margins, phase = [], crawl.phase
    for _ in range(round(duration / STEP)):
        crawl.advance(STEP, allowed)
        if crawl.phase == "swing" and phase == "shift":
            margins.append(crawl.margin())
        phase = crawl.phase
    return margins


def test_shift_for_margin_reaches_the_margin_on_the_way_to_the_incentre():
    triangle = NEUTRAL[[1, 2, 3], :2]  # front_left lifted
    body, margin = shift_for_margin(np.zeros(2), np.zeros(2), triangle, 0.05)
    assert margin == pytest.approx(0.05, abs=1e-6)
    assert stability_margin(body, support_polygon(triangle)) == pytest.approx(0.05, abs=1e-6)
    assert body[0] < 0.0 and body[1] < 0.0  # towards the rear-right side
    already, kept = shift_for_margin(np.array([-0.1, -0.1]), np.zeros(2), triangle, 0.05)
    assert np.allclose(already, [-0.1, -0.1]) and kept >= 0.05


def test_swing_point_starts_and_ends_on_the_ground():
    start, end = np.array([0.0, 0.0]), np.array([0.1, 0.02])
    assert np.allclose(swing_point(start, end, 0.0, 0.04), [0.0, 0.0, 0.0])
    assert np.allclose(swing_point(start, end, 1.0, 0.04), [0.1, 0.02, 0.0])
    assert swing_point(start, end, 0.5, 0.04)[2] == pytest.approx(0.04)


def test_automatic_crawl_walks_at_the_commanded_speed_with_static_margin():
    settings = OnlineCrawlSettings(shift_time=0.5, swing_time=0.5, minimum_margin=0.04)
    crawl = OnlineCrawl(NEUTRAL, np.zeros(2), np.zeros(2), settings)
    crawl.command_velocity(0.02, 0.0)
    cycles = 4
    margins = _run(crawl, cycles * crawl.cycle_time)
    assert len(margins) == 4 * cycles  # every leg stepped every cycle
    assert min(margins) >= 0.04 - 1e-9  # never lifts below the planned margin
    assert crawl.body[0] == pytest.approx(0.02 * cycles * crawl.cycle_time, rel=0.25)
    assert abs(crawl.body[1]) < 0.1
    assert crawl.stance().sum() >= 3


def test_standing_still_takes_no_steps():
    crawl = OnlineCrawl(NEUTRAL, np.zeros(2), np.zeros(2))
    _run(crawl, 20.0)
    assert crawl.steps_taken == 0 and np.allclose(crawl.body, 0.0, atol=0.1)


def test_a_refused_lift_shifts_further_and_never_lifts():
    crawl = OnlineCrawl(NEUTRAL, np.zeros(2), np.zeros(2))
    crawl.command_velocity(0.02, 0.0)
    first = crawl.planned_margin
    _run(crawl, 3.0, allowed=False)
    assert crawl.steps_taken == 0 and crawl.phase == "shift"
    assert "refused" in crawl.refusal and crawl.retries >= 1
    assert crawl.planned_margin >= first + RETRY_MARGIN - 1e-6


def test_shared_control_front_foot_goes_to_the_operator_and_the_rear_follows():
    settings = OnlineCrawlSettings(shift_time=0.5, swing_time=0.5)
    crawl = OnlineCrawl(NEUTRAL, np.zeros(2), np.zeros(2), settings)
    crawl.shared = True
    front_left = LEGS.index("front_left")
    target = NEUTRAL[front_left, :2] + np.array([0.08, 0.0])
    crawl.place("front_left", target)
    crawl.place("front_right", NEUTRAL[LEGS.index("front_right"), :2] + [0.08, 0.0])
    _run(crawl, crawl.cycle_time)
    assert np.allclose(crawl.footholds[front_left], target)
    rear_left = LEGS.index("rear_left")
    _run(crawl, crawl.cycle_time)  # the rear left steps after the front left moved
    assert crawl.footholds[rear_left][0] == pytest.approx(NEUTRAL[rear_left, 0] + 0.08)
    assert np.allclose(crawl.footholds[:, 0], NEUTRAL[:, 0] + 0.08)
    # the body follows the feet: it sways about their centroid (by the margin it plans)
    assert 0.5 * (crawl.shift_from[0] + crawl.shift_to[0]) == pytest.approx(0.08, abs=1e-9)
    assert 0.0 < crawl.body[0] < 0.16


def test_load_shares_unload_the_next_leg_before_it_lifts_and_load_the_landed_one():
    crawl = OnlineCrawl(NEUTRAL, np.zeros(2), np.zeros(2))
    crawl.command_velocity(0.015, 0.0)
    first = LEGS.index(crawl.leg)  # rear_left
    assert np.all(crawl.load_shares() == 1.0)  # start of the shift: all carry
    crawl.advance(crawl.settings.shift_time - 0.2)
    shares = crawl.load_shares(unload_time=0.4)
    assert shares[first] == pytest.approx(0.5) and np.delete(shares, first).min() == 1.0
    _run(crawl, 0.4)  # lifted
    assert crawl.phase == "swing" and crawl.load_shares()[first] == 0.0
    while crawl.phase == "swing":
        crawl.advance(STEP)
    assert crawl.landed == LEGS[first] and crawl.load_shares()[first] == 0.0  # touchdown
    crawl.advance(0.04)
    assert crawl.load_shares(load_time=0.08)[first] == pytest.approx(0.5)


def test_the_body_path_does_not_run_away_from_the_feet():
    settings = OnlineCrawlSettings()
    crawl = OnlineCrawl(NEUTRAL, np.zeros(2), np.zeros(2), settings)
    crawl.command_velocity(0.2, 0.0)  # ten times what the feet can step
    for _ in range(round(30.0 / STEP)):
        crawl.advance(STEP)
        centre = (crawl.footholds - NEUTRAL[:, :2]).mean(axis=0)
        assert np.linalg.norm(crawl.reference - centre) <= 0.5 * settings.max_reach + 1e-9
    assert crawl.steps_taken >= 12 and crawl.reference[0] > 0.2  # still walks forward
