"""Whether the legs can follow a walk plan: the posture the gait is planned about, and a
refusal, before anything is simulated, of a plan whose feet the legs cannot reach.

The crawl's footholds and swings are planned about a *walking posture* (alpha, beta, gamma
of every leg at mid-stance). The default, :data:`.walking.WALKING_ANGLES`, reaches every
sample of the forward and backward gaits; walking sideways, the stride runs along the legs
(they stick out sideways from the thorax) and the swing's lift near the thorax needs more
knee (gamma) than its 95° limit gives: at heading 90° the clamped IK misses the planned
foot by up to 33 mm. :func:`choose_posture` then tries the postures of
:data:`POSTURES` and keeps the first whose plan the legs reach exactly, else the one with
the fewest feet out of reach. :func:`check_reach` refuses a plan that still misses by more than
:data:`REACH_TOLERANCE`, naming the leg, its phase (swing or stance, and where in the
cycle) and the joint limit that stops it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pneumaquad.gait.crawl import LEGS, CrawlGait, gait_offsets
from pneumaquad.robot.builder import RobotModel
from pneumaquad.robot.leg_ik import exact_solutions
from pneumaquad.robot.legs import leg_dh_table

from .walk import CycleSolution, cycle_targets, solve_cycle

__all__ = ["LIMIT_BAND", "LIMIT_SHARE", "PLAN_LIMIT_SHARE", "POSTURES", "REACH_TOLERANCE",
           "UnreachablePlanError", "check_reach", "choose_posture", "largest_miss",
           "limit_share", "plan_miss"]

#: Largest distance [m] between a planned foot and where the clamped IK puts it that a
#: plan may keep (the swing then lifts the foot up to 1 cm less than the 4 cm planned;
#: heading 45° misses by 8.7 mm in its first cycle and walks).
REACH_TOLERANCE = 0.01
#: Walking postures (alpha, beta, gamma) [deg] tried in this order when the default misses:
#: from the default (0, −20, 80) outwards; a lower gamma spreads the feet, a higher beta
#: raises them towards the thorax (measured on crr-quadruped: heading 90° reaches its plan
#: within 2 mm at (0, −10, 65)).
POSTURES = tuple(
    np.radians([0.0, beta, gamma]) for beta, gamma in sorted(
        ((beta, gamma) for beta in (-10.0, -15.0, -20.0, -25.0)
         for gamma in (65.0, 70.0, 75.0, 80.0, 85.0)),
        key=lambda pose: (abs(pose[0] + 20.0) / 5.0 + abs(pose[1] - 80.0) / 5.0, pose))
)
#: A joint within this angle [rad] of a limit counts as at the limit (the walking
#: judgement's "joint limit" reason, :func:`.walking.walking_outcome`).
LIMIT_BAND = np.radians(0.5)
#: Share of a walk a joint may spend at a limit before the walk fails by "joint limit".
LIMIT_SHARE = 0.2
#: Share of a plan's samples a joint may spend at a limit for :func:`choose_posture` to
#: keep its posture: half of :data:`LIMIT_SHARE`, since the joints lag their references
#: (the clockwise turn in place planned gamma at its 95° for 22 % of the cycle and spent
#: 36 % of the turn there).
PLAN_LIMIT_SHARE = 0.5 * LIMIT_SHARE
#: IK samples per cycle when comparing postures (the plan itself uses its own grid).
_SEARCH_SAMPLES = 40


class UnreachablePlanError(ValueError):
    """A walk plan whose feet the legs cannot reach (message: leg, phase, joint limit)."""


@dataclass(frozen=True)
class Miss:
    """The worst sample of a cycle: distance [m] between the planned and the reached foot,
    its leg and its sample index (-1 for a cycle without samples)."""

    distance: float
    leg: int
    sample: int


def largest_miss(cycle: CycleSolution) -> Miss:
    """The sample of ``cycle`` where the clamped IK misses its planned foot most."""
    misses: NDArray[np.float64] = np.linalg.norm(cycle.feet - cycle.targets, axis=2)
    if misses.size == 0:
        return Miss(0.0, 0, -1)
    sample, leg = np.unravel_index(int(np.argmax(misses)), misses.shape)
    return Miss(float(misses[sample, leg]), int(leg), int(sample))


def plan_miss(robot: RobotModel, gait: CrawlGait, samples: int = 40) -> float:
    """Largest distance [m] by which the clamped IK misses a planned foot of ``gait``'s
    steady cycle (and first cycle, with a start-up) on a grid of ``samples``."""
    return max(largest_miss(cycle).distance for cycle in _cycles(robot, gait, samples))


def _cycles(robot: RobotModel, gait: CrawlGait, samples: int) -> list[CycleSolution]:
    """The IK of ``gait``'s steady cycle, and of its first with a start-up."""
    cycles = [solve_cycle(robot, gait, samples)]
    if gait.start_up:
        cycles.append(solve_cycle(robot, gait, samples, first=True))
    return cycles


def limit_share(robot: RobotModel, cycles: list[CycleSolution]) -> float:
    """Largest share, over the joints, of the samples of ``cycles`` that put the joint
    within :data:`LIMIT_BAND` of a limit."""
    lower = robot.lower_limits() + LIMIT_BAND
    upper = robot.upper_limits() - LIMIT_BAND
    angles = np.concatenate([cycle.angles for cycle in cycles])
    return float(np.max(np.mean((angles < lower) | (angles > upper), axis=0)))


def _unreachable_samples(robot: RobotModel, gait: CrawlGait, samples: int) -> int:
    """Planned feet of the steady and the first cycle with no analytic IK answer inside
    the joint limits (no search: cheap enough to compare postures)."""
    tables = [leg_dh_table(robot, leg) for leg in LEGS]
    count = 0
    for first in ((False, True) if gait.start_up else (False,)):
        _, _, targets = cycle_targets(robot, gait, samples, first)
        count += sum(not exact_solutions(table, targets[sample, k])
                     for sample in range(samples) for k, table in enumerate(tables))
    return count


def choose_posture(robot: RobotModel, gait_for: Callable[[np.ndarray], CrawlGait],
                   default: np.ndarray) -> np.ndarray:
    """Walking angles [rad] (alpha, beta, gamma) for the gait ``gait_for(angles)``:
    ``default`` if the legs reach its plan (steady and first cycle) within
    :data:`REACH_TOLERANCE` and no joint spends more than :data:`PLAN_LIMIT_SHARE` of it
    at a limit, else the first of :data:`POSTURES` whose planned feet all have an exact
    IK answer (and that keeps its joints off their limits as long), else the one with the
    fewest that have none."""
    cycles = _cycles(robot, gait_for(default), _SEARCH_SAMPLES)
    if (max(largest_miss(cycle).distance for cycle in cycles) <= REACH_TOLERANCE
            and limit_share(robot, cycles) <= PLAN_LIMIT_SHARE):
        return default
    best, fewest = default, np.inf
    for angles in POSTURES:
        try:
            unreachable = _unreachable_samples(robot, gait_for(angles), _SEARCH_SAMPLES)
        except ValueError:  # e.g. no sway reaches the margin about this posture
            continue
        if unreachable == 0 and limit_share(
                robot, _cycles(robot, gait_for(angles), _SEARCH_SAMPLES)) <= PLAN_LIMIT_SHARE:
            return angles
        if unreachable < fewest:
            best, fewest = angles, unreachable
    return best


def _describe(robot: RobotModel, gait: CrawlGait, cycle: CycleSolution, miss: Miss,
              which: str) -> str:
    leg = LEGS[miss.leg]
    fraction = float(cycle.phases[miss.sample])
    own = (fraction - gait_offsets(gait)[miss.leg]) % 1.0
    swing = 1.0 - gait.duty_factor
    phase = (f"its swing ({100.0 * own / swing:.0f} % through)" if own < swing
             else f"its stance ({100.0 * (own - swing) / gait.duty_factor:.0f} % through)")
    angles = cycle.angles[miss.sample, 3 * miss.leg: 3 * miss.leg + 3]
    names = [name for name in robot.joint_names if name.startswith(leg)]
    lower, upper = robot.lower_limits(), robot.upper_limits()
    stops = []
    for angle, name in zip(angles, names, strict=True):
        j = robot.joint_names.index(name)
        if angle <= lower[j] + 1e-6:
            stops.append(f"{name} at its lower limit {np.degrees(lower[j]):.0f}°")
        elif angle >= upper[j] - 1e-6:
            stops.append(f"{name} at its upper limit {np.degrees(upper[j]):.0f}°")
    reason = ", ".join(stops) or "out of the leg's reach"
    return (f"{leg} cannot reach its planned foot in {phase}, {which} cycle at "
            f"{100.0 * fraction:.0f} % of the cycle: {reason}; it misses by "
            f"{1000.0 * miss.distance:.0f} mm (at most {1000.0 * REACH_TOLERANCE:.0f} mm)")


def check_reach(robot: RobotModel, gait: CrawlGait, cycle: CycleSolution,
                start_up: CycleSolution | None = None) -> None:
    """Raise :class:`UnreachablePlanError` if the clamped IK of the steady ``cycle`` or of
    the first cycle ``start_up`` misses a planned foot by more than
    :data:`REACH_TOLERANCE`; its message names the worst leg, its phase and the joint
    limit that stops it."""
    for which, solved in (("steady", cycle), ("first", start_up)):
        if solved is None:
            continue
        miss = largest_miss(solved)
        if miss.distance > REACH_TOLERANCE:
            raise UnreachablePlanError(_describe(robot, gait, solved, miss, which))
