"""The lateral-sequence wave gait: timing, foot paths, body sway and shared-control lifts."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pneumaquad.gait.crawl import (
    LATERAL_SEQUENCE,
    LEGS,
    CrawlGait,
    body_positions,
    foot_positions_ground,
    foot_targets,
    leg_phases,
    plan_margins,
    refuse_lift,
    stance_flags,
    sway_for_margin,
    swing_order,
)

FEET = np.array([[0.375, 0.28, -0.38], [0.375, -0.28, -0.38],
                 [-0.375, 0.28, -0.38], [-0.375, -0.28, -0.38]])  # LEGS order
PERIOD = 4.0
# Instants over 3 cycles: a 1 ms grid (exact in binary fractions of the cycle).
TIMES = np.arange(0, 3 * 4000) * 1e-3


@pytest.mark.parametrize("duty_factor", [0.75, 0.8, 0.9])
def test_duty_factor_and_one_leg_in_the_air(duty_factor):
    gait = CrawlGait(FEET, duty_factor=duty_factor, period=PERIOD, sway=0.0)
    stance = stance_flags(gait, TIMES)
    assert np.allclose(stance.mean(axis=0), duty_factor, atol=1e-9)
    assert (~stance).sum(axis=1).max() == 1


def test_swing_order_is_the_lateral_sequence():
    gait = CrawlGait(FEET, period=PERIOD)
    assert swing_order(gait) == LATERAL_SEQUENCE
    stance = stance_flags(gait, TIMES[:4000])
    lift_offs = [int(np.flatnonzero(~stance[:, LEGS.index(leg)])[0]) for leg in LEGS]
    assert tuple(LEGS[k] for k in np.argsort(lift_offs)) == LATERAL_SEQUENCE
    assert swing_order(CrawlGait(FEET, heading=np.pi, sway=0.0))[0] == "front_left"


@pytest.mark.parametrize("sway", [0.0, 1.0])
@pytest.mark.parametrize("heading", [0.0, 0.6])
def test_stance_feet_stand_still_on_the_ground(sway, heading):
    gait = CrawlGait(FEET, period=PERIOD, stride=0.12, sway=sway, heading=heading)
    targets = foot_targets(gait, TIMES)
    ground = targets[..., :2] + body_positions(gait, TIMES)[:, None, :]
    stance = stance_flags(gait, TIMES)
    assert np.allclose(ground, foot_positions_ground(gait, TIMES)[..., :2])
    travel = np.diff(body_positions(gait, TIMES[[0, 4000]]), axis=0)[0]  # one cycle
    assert np.allclose(travel, 0.12 / 0.8 * gait.direction, atol=1e-12)  # sway periodic
    for k in range(4):
        still = stance[1:, k] & stance[:-1, k]
        steps = np.linalg.norm(np.diff(ground[:, k], axis=0), axis=1)
        assert steps[still].max() < 1e-12
        assert np.all(targets[stance[:, k], k, 2] == FEET[k, 2])


def test_swing_lifts_and_lands_smoothly():
    gait = CrawlGait(FEET, period=PERIOD, stride=0.1, step_height=0.05)
    step = 1e-3
    times = np.arange(0, 4000) * step
    heights = foot_positions_ground(gait, times)[..., 2]
    phases = leg_phases(gait, times)
    swing = 1.0 - gait.duty_factor
    assert heights.max() == pytest.approx(0.05, rel=1e-6)
    assert heights.min() == 0.0
    for edge in (0.0, swing):  # lift-off and touchdown: height and vertical speed ~ 0
        near = np.abs(phases - edge) < 2e-3
        assert heights[near].max() < 1e-4
    vertical_speed = np.abs(np.diff(heights, axis=0)) / step
    assert vertical_speed.max() < 1.1 * np.pi * 0.05 / (swing * PERIOD)
    ground = foot_positions_ground(gait, times)[..., :2]
    foot_speed = np.linalg.norm(np.diff(ground, axis=0), axis=-1) / step
    assert foot_speed.max() < 2.1 * gait.speed / swing  # no jumps (cycloid peak: 2 v_mean)


def test_margin_without_sway_is_small_and_zero_at_three_quarters():
    _, margins = plan_margins(CrawlGait(FEET, duty_factor=0.75, stride=0.1, sway=0.0))
    assert margins.min() == pytest.approx(0.0, abs=1e-12)
    _, margins = plan_margins(CrawlGait(FEET, duty_factor=0.8, stride=0.1, sway=0.0))
    assert 0.0 < margins.min() < 0.01


def test_sway_for_margin_meets_the_minimum():
    gait = sway_for_margin(CrawlGait(FEET, stride=0.1), 0.04)
    assert 0.0 < gait.sway < 1.0
    _, margins = plan_margins(gait, samples=800)
    assert margins.min() >= 0.04 - 1e-4
    with pytest.raises(ValueError, match="full sway"):
        sway_for_margin(CrawlGait(FEET, stride=0.1), 0.5)


def test_invalid_gaits_are_refused():
    with pytest.raises(ValueError, match="duty factor"):
        CrawlGait(FEET, duty_factor=0.7)
    with pytest.raises(ValueError, match="sway"):
        CrawlGait(FEET, duty_factor=0.75, sway=1.0)
    with pytest.raises(ValueError, match="transfer gap"):  # 2·0.15 + 0.25 > 0.5
        CrawlGait(FEET, duty_factor=0.85, transfer_gap=0.25)


@pytest.mark.parametrize("gap", [0.0, 0.04, 0.1])
def test_transfer_gap_keeps_four_feet_down_between_rear_touchdown_and_front_lift_off(gap):
    gait = CrawlGait(FEET, duty_factor=0.9, period=PERIOD, stride=0.1, transfer_gap=gap)
    stance = stance_flags(gait, TIMES)
    assert np.allclose(stance.mean(axis=0), 0.9, atol=1e-9)  # duty factor unchanged
    assert (~stance).sum(axis=1).max() == 1
    assert swing_order(gait) == LATERAL_SEQUENCE
    cycle = stance[:4000]
    for rear, front in (("rear_left", "front_left"), ("rear_right", "front_right")):
        touchdown = np.flatnonzero(~cycle[:, LEGS.index(rear)])[-1] + 1
        lift_off = np.flatnonzero(~cycle[:, LEGS.index(front)])[0]
        assert (lift_off - touchdown) * 1e-3 == pytest.approx(gap * PERIOD, abs=1.5e-3)
        assert np.all(cycle[touchdown:lift_off])  # four feet down in between
    # stance feet still stand still, and the body still travels one stride per β·T
    ground = foot_targets(gait, TIMES)[..., :2] + body_positions(gait, TIMES)[:, None, :]
    for k in range(4):
        still = stance[1:, k] & stance[:-1, k]
        assert np.abs(np.diff(ground[:, k], axis=0))[still].max() < 1e-12
    margins = plan_margins(sway_for_margin(gait, 0.04), samples=800)[1]
    assert margins.min() >= 0.04 - 1e-4


def test_start_up_begins_from_the_symmetric_stance_and_joins_the_steady_gait():
    steady = sway_for_margin(CrawlGait(FEET, duty_factor=0.9, period=PERIOD, stride=0.1,
                                       transfer_gap=0.04), 0.04)
    gait = dataclasses.replace(steady, start_up=True)
    ground = foot_positions_ground(gait, TIMES)
    assert np.allclose(ground[0, :, :2], FEET[:, :2])  # neutral feet at t = 0
    assert np.ptp(ground[0, :, 0]) == pytest.approx(0.75)  # left and right abreast
    stance = stance_flags(gait, TIMES)
    for k in range(4):  # each foot stays neutral until its first lift-off
        first_lift = np.flatnonzero(~stance[:, k])[0]
        assert np.allclose(ground[:first_lift, k, :2], FEET[k, :2])
    after = TIMES >= PERIOD  # from the second cycle on, the steady gait exactly
    assert np.allclose(ground[after], foot_positions_ground(steady, TIMES[after]))
    # the first swings are cycloids too, from the neutral foothold: no jump; those of
    # the legs that lift last are longer (their feet stood while the body moved)
    step = np.linalg.norm(np.diff(ground[..., :2], axis=0), axis=-1)
    steady_step = np.linalg.norm(np.diff(ground[after][..., :2], axis=0), axis=-1)
    assert steady_step.max() < step.max() < 1.25 * steady_step.max()
    # the plan's margin is that of a steady cycle; the start-up's is reported by the plan
    assert plan_margins(gait)[1] == pytest.approx(plan_margins(steady)[1])


def test_refuse_lift_keeps_the_centre_of_mass_supported():
    feet = FEET[:, :2]
    stance = np.ones(4, dtype=bool)
    centre = np.zeros(2)
    # Centre of mass on the diagonal: every lift leaves it on the boundary (margin 0).
    assert not refuse_lift(feet, stance, LEGS.index("rear_left"), centre)
    right = np.array([0.0, -0.1])  # shifted to the right
    assert refuse_lift(feet, stance, LEGS.index("front_right"), right)
    assert not refuse_lift(feet, stance, LEGS.index("rear_left"), right)
    assert refuse_lift(feet, stance, LEGS.index("rear_left"), right, minimum_margin=0.1)
    three = stance.copy()
    three[LEGS.index("rear_left")] = False
    assert refuse_lift(feet, three, LEGS.index("front_left"), right)  # two feet: a line


def test_the_gait_roles_follow_the_direction_of_travel():
    """Walking sideways, "rear" and "front" are the legs behind and ahead along the travel
    and the body sways across it (along x); forward and backward keep their sequences."""
    import dataclasses
    import math

    from pneumaquad.gait.crawl import CrawlGait, sway_axis, swing_order, travel_quarter

    assert [travel_quarter(math.radians(h)) for h in (0, 44, 45, 46, 90, 135, 180, 270, 315)
            ] == [0, 0, 0, 1, 1, 2, 2, 3, 0]
    feet = np.array([[0.375, 0.356, -0.38], [0.375, -0.356, -0.38],
                     [-0.375, 0.356, -0.38], [-0.375, -0.356, -0.38]])
    forward = CrawlGait(feet, duty_factor=0.9, period=8.0, stride=0.144, heading=0.0)
    assert swing_order(forward) == ("rear_left", "front_left", "rear_right", "front_right")
    assert sway_axis(forward) == 1
    left = dataclasses.replace(forward, heading=math.pi / 2)  # travel along +y
    # behind the travel: the right legs; on its left: the rear legs
    assert swing_order(left) == ("rear_right", "rear_left", "front_right", "front_left")
    assert sway_axis(left) == 0
    right = dataclasses.replace(forward, heading=-math.pi / 2)
    assert swing_order(right) == ("front_left", "front_right", "rear_left", "rear_right")
    # a sideways body sways along x only; its travel is along y
    from pneumaquad.gait.crawl import body_positions

    times = np.linspace(0.0, 8.0, 81)
    path = body_positions(left, times)
    assert np.ptp(path[:, 0]) > 0.02  # sway across the travel
    assert path[:, 1] == pytest.approx(left.speed * times)


def test_a_sideways_plan_keeps_its_static_margin():
    import math

    from pneumaquad.gait.crawl import CrawlGait, plan_margins, sway_for_margin

    feet = np.array([[0.375, 0.356, -0.38], [0.375, -0.356, -0.38],
                     [-0.375, 0.356, -0.38], [-0.375, -0.356, -0.38]])
    gait = sway_for_margin(CrawlGait(feet, duty_factor=0.9, period=8.0, stride=0.144,
                                     heading=math.pi / 2, transfer_gap=0.04), 0.06)
    _, margins = plan_margins(gait)
    assert margins.min() >= 0.06 - 1e-6
