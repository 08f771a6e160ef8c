"""Baselines of the Gymnasium environment (docs/gymnasium.md): the crawl gait and random.

Each policy runs ``--episodes`` episodes of ``pneumaquad/Quadruped-v0`` (default options:
20 ms control period, reset noise ±0.02 rad, the registration's 1000-step limit = 20 s),
seeded 0, 1, 2, …; it prints per policy the mean and spread of the episode return, the
forward distance of the thorax [m], the lateral offset at the end [m], the air drawn
[NL], the episode length [steps] and the number of falls.

Policies:

* **crawl gait** (``action="angles"``): :class:`pneumaquad.interop.CrawlGaitPolicy`,
  the crawl gait of ``pneumaquad robot walk`` (2 cm/s, 8 s cycles) as joint-angle
  references, after a 1 s lead-in from the initial pose to the gait's first pose;
* **random angles** (``action="angles"``): uniform joint-angle references within the
  joint limits, a new draw every step;
* **random voltages** (``action="voltage"``): uniform valve voltages in 0–10 V;
* **hold** (``action="angles"``): the initial pose held (standing still, for reference).

    .venv/bin/python docs/examples/gym_baselines.py [--episodes 5]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import gymnasium
import numpy as np

import pneumaquad.interop as interop
from pneumaquad.interop import CrawlGaitPolicy, RandomPolicy

Policy = Callable[[np.ndarray], np.ndarray]


def run(action: str, make_policy: Callable[[gymnasium.Env], Policy], episodes: int
        ) -> dict[str, np.ndarray]:
    """Episode figures of one policy (arrays over the episodes)."""
    env = gymnasium.make(interop.ENV_ID, action=action)
    policy = make_policy(env)
    figures: dict[str, list[float]] = {key: [] for key in
                                       ("return", "distance", "lateral", "air", "steps", "fell")}
    for episode in range(episodes):
        observation, info = env.reset(seed=episode)
        getattr(policy, "reset", lambda: None)()
        total, steps, fell = 0.0, 0, False
        while True:
            observation, reward, terminated, truncated, info = env.step(policy(observation))
            total += float(reward)
            steps += 1
            if terminated or truncated:
                fell = bool(info["fell"])
                break
        figures["return"].append(total)
        figures["distance"].append(info["distance [m]"])
        figures["lateral"].append(info["lateral offset [m]"])
        figures["air"].append(info["air consumed [NL]"])
        figures["steps"].append(steps)
        figures["fell"].append(fell)
    env.close()
    return {key: np.array(values) for key, values in figures.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=5)
    args = parser.parse_args()

    def hold(env: gymnasium.Env) -> Policy:
        initial = env.unwrapped.initial_angles  # type: ignore[attr-defined]
        return lambda observation: initial

    policies: list[tuple[str, str, Callable[[gymnasium.Env], Policy]]] = [
        ("crawl gait", "angles", lambda env: CrawlGaitPolicy(
            control_period=env.unwrapped.control_period)),  # type: ignore[attr-defined]
        ("random angles", "angles", lambda env: RandomPolicy(env.action_space, seed=0)),
        ("random voltages", "voltage", lambda env: RandomPolicy(env.action_space, seed=0)),
        ("hold initial pose", "angles", hold),
    ]
    print(f"{interop.ENV_ID}: {args.episodes} episodes per policy, seeds 0–{args.episodes - 1}, "
          "20 ms control period, at most 1000 steps (20 s)\n")
    header = ("policy", "return mean (min–max)", "distance [m] mean (min–max)",
              "lateral end [m] mean |.|", "air [NL] mean", "steps mean", "falls")
    print(" | ".join(header))
    for name, action, make_policy in policies:
        started = time.perf_counter()
        f = run(action, make_policy, args.episodes)
        wall = time.perf_counter() - started
        print(f"{name} | {f['return'].mean():.2f} ({f['return'].min():.2f}–"
              f"{f['return'].max():.2f}) | {f['distance'].mean():.3f} "
              f"({f['distance'].min():.3f}–{f['distance'].max():.3f}) | "
              f"{np.abs(f['lateral']).mean():.3f} | {f['air'].mean():.2f} | "
              f"{f['steps'].mean():.0f} | {int(f['fell'].sum())}/{args.episodes}"
              f"   ({wall:.1f} s wall)")


if __name__ == "__main__":
    main()
