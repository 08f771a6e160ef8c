"""Interoperability: the simulator in other tools' ecosystems.

The Gymnasium environment of the quadruped (:mod:`.gym_env`, docs/gymnasium.md) is
registered as :data:`ENV_ID` when this package is imported::

    import gymnasium
    import pneumaquad.interop  # registers pneumaquad/Quadruped-v0

    env = gymnasium.make("pneumaquad/Quadruped-v0", action="voltage")

(or, without the import, ``gymnasium.make("pneumaquad.interop:pneumaquad/Quadruped-v0")``).
The registration names the environment by an entry-point string, so importing this package
loads neither MuJoCo nor numba; :class:`QuadrupedEnv` and the baseline policies are loaded
on first use.
"""

from importlib import import_module
from typing import Any

import gymnasium

#: The environment's Gymnasium id.
ENV_ID = "pneumaquad/Quadruped-v0"
#: Steps after which ``gymnasium.make`` truncates an episode (20 s at the default 20 ms).
MAX_EPISODE_STEPS = 1000

if ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=ENV_ID,
        entry_point="pneumaquad.interop.gym_env:QuadrupedEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
    )

#: public name -> module that defines it
_PUBLIC = {
    "QuadrupedEnv": "pneumaquad.interop.gym_env",
    "CrawlGaitPolicy": "pneumaquad.interop.gym_policies",
    "RandomPolicy": "pneumaquad.interop.gym_policies",
    "OBSERVATION_LAYOUT": "pneumaquad.interop.gym_terms",
    "observation_slices": "pneumaquad.interop.gym_terms",
}

__all__ = ["ENV_ID", "MAX_EPISODE_STEPS", *_PUBLIC]


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first use (PEP 562)."""
    module_name = _PUBLIC.get(name)
    if module_name is None:
        raise AttributeError(f"module 'pneumaquad.interop' has no attribute {name!r}")
    value = getattr(import_module(module_name), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
