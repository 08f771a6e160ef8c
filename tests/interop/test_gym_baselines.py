"""The crawl-gait baseline walks forward in the Gymnasium environment."""

from __future__ import annotations

import gymnasium
import numpy as np

import pneumaquad.interop as interop
from pneumaquad.interop import CrawlGaitPolicy


def test_crawl_gait_policy_walks_the_thorax_forward_without_a_fall() -> None:
    policy = CrawlGaitPolicy()
    env = gymnasium.make(interop.ENV_ID, action="angles")
    observation, _ = env.reset(seed=0)
    policy.reset()
    total, info = 0.0, {}
    for _ in range(750):  # 15 s: the 1 s lead-in, the start-up cycle and most of one more
        action = policy(observation)
        assert env.action_space.contains(action)
        observation, reward, terminated, truncated, info = env.step(action)
        total += reward
        assert not (terminated or truncated)
    assert info["distance [m]"] > 0.15  # planned 2 cm/s over 14 s: 0.28 m
    assert abs(info["lateral offset [m]"]) < 0.2
    assert total > 0.0


def test_crawl_gait_policy_leads_in_then_repeats_its_steady_cycle() -> None:
    policy = CrawlGaitPolicy(lead_in=0.1)
    observation = np.zeros(62)
    observation[:12] = 0.1
    actions = np.array([policy(observation) for _ in range(5 + 3 * policy.steps_per_cycle)])
    np.testing.assert_allclose(actions[4], policy.initial_angles)
    np.testing.assert_allclose(actions[0], 0.1 + 0.2 * (policy.initial_angles - 0.1))
    cycle = policy.steps_per_cycle
    start = 5 + cycle  # the steady cycle
    np.testing.assert_array_equal(actions[start : start + cycle],
                                  actions[start + cycle : start + 2 * cycle])
    policy.reset()
    np.testing.assert_array_equal(policy(observation), actions[0])
