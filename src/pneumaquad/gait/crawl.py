"""The lateral-sequence wave gait ("crawl") of a quadruped, as pure functions of time.

Thesis 3.3: the CRR's shared-control gait moved the robot forward "without ever risking
loss of static stability". The statically stable quadruped gait studied by McGhee & Frank
(1968) is the *wave gait*: legs swing one at a time, a rear leg and then the front leg on
the same side, then the rear and front legs of the other side — the **lateral sequence**
rear_left → front_left → rear_right → front_right. Among the regular creeping gaits it
is the one with the largest longitudinal stability margin.

Phases (cycle fractions, 0 = lift-off of rear_left, β the duty factor ≥ 0.75, g the
transfer gap, 0 by default): rear_left lifts at 0, front_left at 1 − β + g (with g = 0 as
rear_left touches down), rear_right at 0.5, front_right at 1.5 − β + g. Each leg swings
for (1 − β) of the cycle, so at most one leg is in the air; for β > 0.75 two four-legged
phases, [2(1 − β) + g, 0.5] and [2.5 − 2β + g, 1] — i.e. after each side's pair of
swings — are left for shifting the body sideways (sway). The gap g is a short
four-legged phase between a side's rear touchdown and its front lift-off, in which a
force-controlled stance can move the load off the front leg before it lifts (without
it, the load jumps from the front leg to the rear one at the instant of lift-off).
Walking backwards (|heading| > 90°) swaps the roles of front and rear legs.

The roles follow the direction of travel: a heading nearer to sideways than to forward or
backward (|sin| > |cos|) turns the gait by a quarter, so that "rear" and "front" are the
legs behind and ahead along the travel and the sway is along the body's x axis, across the
travel (:func:`travel_quarter`). Without it, a sideways walk swings its legs in the
forward sequence and sways the body along its own travel, and the legs run out of reach
(heading 90° at the default stride: 296 of 800 IK samples beyond a joint limit).

Frames: the *body frame* has x forward, y left, z up, origin at the thorax origin, axes
fixed to the body (which does not turn). The *ground frame* is the body frame at t = 0
without sway, fixed to the ground. Feet stand still in the ground frame during stance;
a swing moves the foot by one cycle's body travel on a cycloid (zero velocity and
acceleration at lift-off and touchdown) while lifting it by (1 − cos)/2 (zero height and
vertical speed at both ends).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .stability import stability_margin, support_margins, support_polygon

__all__ = [
    "LATERAL_SEQUENCE",
    "LEGS",
    "CrawlGait",
    "body_positions",
    "body_sway",
    "foot_positions_ground",
    "foot_targets",
    "gait_offsets",
    "leg_phases",
    "lift_off_offsets",
    "margin_after_lift",
    "plan_margins",
    "refuse_lift",
    "stance_flags",
    "stance_travel",
    "sway_axis",
    "sway_for_margin",
    "sway_shifts",
    "swing_order",
    "travel_quarter",
]

Array = NDArray[np.float64]
#: Leg order of every (..., 4, ...) array here (that of ``RobotModel.legs``).
LEGS = ("front_left", "front_right", "rear_left", "rear_right")
_PHASE_TOLERANCE = 1e-9  # [cycle fraction] rounding of the phase at a touchdown
#: Swing order of the forward wave gait (McGhee & Frank's lateral sequence).
LATERAL_SEQUENCE = ("rear_left", "front_left", "rear_right", "front_right")


@dataclasses.dataclass(frozen=True)
class CrawlGait:
    """Parameters of a lateral-sequence wave gait.

    Attributes
    ----------
    neutral_feet : (4, 3) array [m]
        Foot positions in the body frame at the middle of stance, in :data:`LEGS` order
        (z: minus the body height).
    duty_factor : float
        β, fraction of the cycle each leg is in stance, 0.75 ≤ β < 1.
    period : float [s]
        Cycle period T.
    stride : float [m]
        Distance a stance foot travels relative to the body (= body travel per stance).
    step_height : float [m]
        Foot lift at mid-swing.
    heading : float [rad]
        Direction of travel in the body frame (0 forward, π/2 left).
    turn : float [rad]
        Rotation of the body about its vertical axis per stance (counter-clockwise
        positive), the angular counterpart of ``stride``: relative to the body, each
        stance foot turns by −turn about the body origin (0: the body does not turn; with
        a stride, the body walks an arc).
    sway : float
        Fraction of the sideways body shift towards the support triangles' incentres
        (0: no sway, 1: the centre of mass over the incentres' mean lateral position).
    com_offset : (2,) array [m]
        Ground projection of the centre of mass in the body frame.
    lift_fraction : float
        Fraction ℓ < 0.5 of the swing at its start (and at its end) in which the foot only
        rises (lowers), without moving along the ground: a foot still carrying load at
        lift-off is not dragged. 0: rise and travel together (one cycloid).
    """

    neutral_feet: Array
    duty_factor: float = 0.8
    period: float = 4.0
    stride: float = 0.1
    step_height: float = 0.04
    heading: float = 0.0
    sway: float = 1.0
    com_offset: Array = dataclasses.field(default_factory=lambda: np.zeros(2))
    lift_fraction: float = 0.0
    transfer_gap: float = 0.0
    start_up: bool = False
    turn: float = 0.0

    def __post_init__(self) -> None:
        feet = np.array(self.neutral_feet, dtype=float)
        if feet.shape != (4, 3):
            raise ValueError(f"neutral_feet must have shape (4, 3), got {feet.shape}")
        object.__setattr__(self, "neutral_feet", feet)
        object.__setattr__(self, "com_offset", np.array(self.com_offset, dtype=float))
        if not 0.75 <= self.duty_factor < 1.0:
            raise ValueError(f"duty factor {self.duty_factor} must be in [0.75, 1)")
        if self.period <= 0.0 or self.stride < 0.0 or self.step_height < 0.0:
            raise ValueError("period must be positive, stride and step height non-negative")
        if not 0.0 <= self.lift_fraction < 0.5:
            raise ValueError(f"lift fraction {self.lift_fraction} must be in [0, 0.5)")
        if self.sway != 0.0 and self.duty_factor <= 0.75:
            raise ValueError("body sway needs four-legged phases: duty factor > 0.75")
        side = 2.0 * (1.0 - self.duty_factor) + self.transfer_gap
        if self.transfer_gap < 0.0 or side > 0.5 + 1e-12:
            raise ValueError(f"transfer gap {self.transfer_gap} must be in "
                             f"[0, {2.0 * self.duty_factor - 1.5:.3g}] (2β − 1.5): a side's "
                             "two swings and the gap must fit in half a cycle")
        if self.sway != 0.0 and side >= 0.5 - 1e-12:
            raise ValueError(f"body sway needs four-legged phases: with duty factor "
                             f"{self.duty_factor} a transfer gap of {self.transfer_gap} "
                             "leaves none")

    @property
    def speed(self) -> float:
        """Body speed [m/s]: stride / (β T)."""
        return self.stride / (self.duty_factor * self.period)

    @property
    def yaw_rate(self) -> float:
        """Body yaw rate [rad/s]: turn / (β T)."""
        return self.turn / (self.duty_factor * self.period)

    @property
    def direction(self) -> Array:
        """Unit direction of travel (2,) in the body frame."""
        return np.array([math.cos(self.heading), math.sin(self.heading)])


def lift_off_offsets(duty_factor: float, backward: bool = False,
                     transfer_gap: float = 0.0) -> Array:
    """Lift-off time of each leg (:data:`LEGS` order) as a cycle fraction in [0, 1)."""
    second = 1.0 - duty_factor + transfer_gap  # a side's second lift-off
    rear_left, front_left, rear_right, front_right = 0.0, second, 0.5, 0.5 + second
    if backward:  # the front legs lead: front_left → rear_left → front_right → rear_right
        front_left, rear_left, front_right, rear_right = 0.0, second, 0.5, 0.5 + second
    return np.array([front_left, front_right, rear_left, rear_right])


def travel_quarter(heading: float) -> int:
    """Quarter turn (0 forward, 1 left, 2 backward, 3 right) nearest to ``heading`` [rad]:
    the body axis the gait's roles are taken along. Diagonals (|sin| = |cos|) count as
    forward or backward."""
    cos, sin = math.cos(heading), math.sin(heading)
    if abs(sin) > abs(cos) + 1e-9:  # 135° is a tie, not 1e-16 more sideways
        return 1 if sin > 0.0 else 3
    return 0 if cos >= 0.0 else 2


#: Legs in the roles (rear_left, front_left, rear_right, front_right) of the forward
#: sequence when the travel is along +y (quarter 1) or −y (quarter 3): the legs behind
#: and ahead, on the left and the right, of the direction of travel.
_SIDEWAYS_ROLES = {
    1: ("rear_right", "rear_left", "front_right", "front_left"),
    3: ("front_left", "front_right", "rear_left", "rear_right"),
}


def gait_offsets(gait: CrawlGait) -> Array:
    """Lift-off of each leg (:data:`LEGS` order) [cycle fraction] for the gait's heading
    (:func:`lift_off_offsets` with the roles of :func:`travel_quarter`)."""
    quarter = travel_quarter(gait.heading)
    if quarter in (0, 2):
        return lift_off_offsets(gait.duty_factor, backward=quarter == 2,
                                transfer_gap=gait.transfer_gap)
    forward = lift_off_offsets(gait.duty_factor, transfer_gap=gait.transfer_gap)
    offsets = np.empty(len(LEGS))
    for role, leg in zip(LATERAL_SEQUENCE, _SIDEWAYS_ROLES[quarter], strict=True):
        offsets[LEGS.index(leg)] = forward[LEGS.index(role)]
    return offsets


def sway_axis(gait: CrawlGait) -> int:
    """Body axis the sway moves along: 1 (y) walking forward or backward, 0 (x) sideways."""
    return 0 if travel_quarter(gait.heading) in (1, 3) else 1



def swing_order(gait: CrawlGait) -> tuple[str, ...]:
    """Leg names in the order they swing, starting with the first lift-off of a cycle."""
    return tuple(LEGS[k] for k in np.argsort(gait_offsets(gait), kind="stable"))


def leg_phases(gait: CrawlGait, times: ArrayLike) -> Array:
    """Phase (n, 4) in [0, 1) of each leg since its lift-off, at ``times`` (n,) [s]."""
    cycles = np.asarray(times, dtype=float)[..., None] / gait.period - gait_offsets(gait)
    return cycles - np.floor(cycles)


def stance_flags(gait: CrawlGait, times: ArrayLike) -> NDArray[np.bool_]:
    """True (n, 4) where a leg is in stance (a touching-down foot counts as stance)."""
    # a touchdown exactly at another leg's lift-off must not leave both in the air
    # because of rounding in the phase (e.g. t / T = 9.2 → 0.19999…)
    return leg_phases(gait, times) >= 1.0 - gait.duty_factor - _PHASE_TOLERANCE


def foot_positions_ground(gait: CrawlGait, times: ArrayLike) -> Array:
    """Feet (n, 4, 3) [m] in the ground frame: xy on the ground, z = height above it."""
    times = np.asarray(times, dtype=float)
    swing = 1.0 - gait.duty_factor
    cycles = times[..., None] / gait.period - gait_offsets(gait)
    count = np.floor(cycles)
    phase = cycles - count
    touchdown = (count + gait_offsets(gait) + swing) * gait.period  # of the current cycle
    travel = gait.speed * gait.period  # per cycle = stride / β
    along = 0.5 * gait.stride + gait.speed * touchdown  # foothold along the direction
    progress = np.clip(phase / swing, 0.0, 1.0)
    in_swing = phase < swing
    edge = gait.lift_fraction
    moving = np.clip((progress - edge) / (1.0 - 2.0 * edge), 0.0, 1.0)
    cycloid = moving - np.sin(2.0 * math.pi * moving) / (2.0 * math.pi)
    previous = along - travel  # where the swinging foot lifted off
    if gait.start_up:  # neutral until the first lift-off, from which the first swing starts
        previous = np.where(count == 0, 0.0, previous)
        along = np.where(count < 0, 0.0, along)
    along = np.where(in_swing, previous + (along - previous) * cycloid, along)
    if edge > 0.0:  # rise over ℓ, stay up, lower over the last ℓ (half-cosine ramps)
        ramp = np.clip(np.minimum(progress, 1.0 - progress) / edge, 0.0, 1.0)
        height = 0.5 * (1.0 - np.cos(math.pi * ramp))
    else:
        height = 0.5 * (1.0 - np.cos(2.0 * math.pi * progress))
    lift = np.where(in_swing, gait.step_height * height, 0.0)
    feet = np.empty((*times.shape, 4, 3))
    feet[..., :2] = gait.neutral_feet[:, :2] + along[..., None] * gait.direction
    feet[..., 2] = lift
    return feet


def _smoothstep(fraction: Array) -> Array:
    x = np.clip(fraction, 0.0, 1.0)
    return x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)


def _incentre(triangle: Array) -> Array:
    opposite = np.linalg.norm(np.roll(triangle, -1, axis=0) - np.roll(triangle, -2, axis=0),
                              axis=1)
    return opposite @ triangle / opposite.sum()


def sway_shifts(gait: CrawlGait) -> Array:
    """Body shift [m] across the travel (along :func:`sway_axis`) while the first and while
    the second side swings.

    For each swing, the incentre of the support triangle of the other three feet at
    mid-swing (planned without sway); a side's shift puts the centre of mass over the
    mean lateral position of its two swings' incentres, times ``gait.sway``.
    """
    still = dataclasses.replace(gait, sway=0.0, start_up=False)  # a steady cycle
    offsets = gait_offsets(gait)
    axis = sway_axis(gait)
    swing = 1.0 - gait.duty_factor
    shifts = np.zeros(2)
    for side, first in enumerate((0.0, 0.5)):
        lateral = []
        for start in (first, first + swing + gait.transfer_gap):
            time = (start + 0.5 * swing) * gait.period
            leg = int(np.argmin(np.abs(offsets - start)))
            feet = foot_targets(still, np.array([time]))[0, :, :2]
            lateral.append(_incentre(np.delete(feet, leg, axis=0))[axis])
        shifts[side] = gait.sway * (np.mean(lateral) - gait.com_offset[axis])
    return shifts


def _lateral_sway(gait: CrawlGait, times: Array) -> Array:
    if gait.sway == 0.0:
        return np.zeros_like(times)
    first, second = sway_shifts(gait)
    pair = 2.0 * (1.0 - gait.duty_factor) + gait.transfer_gap  # a side's two swings
    window = 0.5 - pair  # four-legged phase
    cycle = np.mod(times / gait.period, 1.0)
    to_second = first + (second - first) * _smoothstep((cycle - pair) / window)
    to_first = second + (first - second) * _smoothstep((cycle - 0.5 - pair) / window)
    return np.where(cycle < 0.5, to_second, to_first)


def body_sway(gait: CrawlGait, times: ArrayLike) -> Array:
    """The body's sway (n, 2) [m] in the ground frame: its offset from steady travel."""
    times = np.asarray(times, dtype=float)
    sway = np.zeros((*times.shape, 2))
    sway[..., sway_axis(gait)] = _lateral_sway(gait, times)
    return sway


def body_positions(gait: CrawlGait, times: ArrayLike) -> Array:
    """Body origin (n, 2) [m] in the ground frame: travel at ``gait.speed`` plus sway."""
    times = np.asarray(times, dtype=float)
    return gait.speed * times[..., None] * gait.direction + body_sway(gait, times)


def stance_travel(gait: CrawlGait, times: ArrayLike) -> Array:
    """Each foot's displacement (n, 4) relative to the body, as a fraction of the stride:
    +½ at touchdown, −½ at lift-off, back from −½ to +½ in the swing (0 before the first
    lift-off of a start-up; a straight gait's foot is at neutral + fraction·stride along
    the heading, apart from the sway)."""
    times = np.asarray(times, dtype=float)
    span = gait.duty_factor * gait.period  # the stride of a unit speed
    unit = dataclasses.replace(gait, stride=span, heading=0.0, sway=0.0, turn=0.0)
    along = foot_positions_ground(unit, times)[..., 0] - times[..., None]
    return (along - gait.neutral_feet[:, 0]) / span


def foot_targets(gait: CrawlGait, times: ArrayLike) -> Array:
    """Feet (n, 4, 3) [m] in the body frame at ``times`` (n,) [s] (body travel, turn and
    sway)."""
    feet = foot_positions_ground(gait, times)
    feet[..., :2] -= body_positions(gait, times)[..., None, :]
    if gait.turn != 0.0:  # each foot turned about the body origin by its share of the turn
        angle = stance_travel(gait, times) * gait.turn
        x, y = gait.neutral_feet[:, 0], gait.neutral_feet[:, 1]
        cosine, sine = np.cos(angle), np.sin(angle)
        feet[..., 0] += cosine * x - sine * y - x
        feet[..., 1] += sine * x + cosine * y - y
    feet[..., 2] += gait.neutral_feet[:, 2]
    return feet


def plan_margins(gait: CrawlGait, times: ArrayLike | None = None,
                 samples: int = 200) -> tuple[Array, Array]:
    """Static stability margin [m] of the plan (body and feet as planned, no dynamics).

    Parameters
    ----------
    gait : CrawlGait
    times : (n,) array [s], optional
        Default: ``samples`` instants over one steady cycle (with ``gait.start_up``
        the second: the start-up cycle, from the symmetric stance, is not periodic).
    samples : int

    Returns
    -------
    times : (n,) [s]
    margins : (n,) [m]
        Signed distance of ``gait.com_offset`` to the stance feet's support polygon.
    """
    if times is None:
        first = gait.period if gait.start_up else 0.0
        times = np.linspace(first, first + gait.period, samples, endpoint=False)
    times = np.asarray(times, dtype=float)
    stance = stance_flags(gait, times)
    if not stance.any(axis=-1).all():
        raise ValueError("no support: an instant of the plan has no foot in stance")
    margins = support_margins(foot_targets(gait, times), stance, gait.com_offset)
    return times, margins


def sway_for_margin(gait: CrawlGait, minimum_margin: float, samples: int = 200,
                    iterations: int = 30) -> CrawlGait:
    """The gait with the least sway (fraction in [0, 1], bisection) whose planned static
    margin over a steady cycle is at least ``minimum_margin`` [m] (small sways spare the legs'
    sideways reach).

    Raises
    ------
    ValueError
        If even full sway (``sway=1``) stays below ``minimum_margin``.
    """
    def least(sway: float) -> float:
        return float(plan_margins(dataclasses.replace(gait, sway=sway),
                                  samples=samples)[1].min())

    if gait.duty_factor > 0.75 and least(1.0) < minimum_margin:
        raise ValueError(f"full sway gives {1e3 * least(1.0):.1f} mm < "
                         f"{1e3 * minimum_margin:.1f} mm")
    if least(0.0) >= minimum_margin:
        return dataclasses.replace(gait, sway=0.0)
    if gait.duty_factor <= 0.75:
        raise ValueError("body sway needs four-legged phases: duty factor > 0.75")
    low, high = 0.0, 1.0
    for _ in range(iterations):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if least(middle) >= minimum_margin else (middle, high)
    return dataclasses.replace(gait, sway=high)


def margin_after_lift(feet_xy: ArrayLike, stance: ArrayLike, leg: int,
                      com_xy: ArrayLike) -> float:
    """Static margin [m] with ``leg`` (index) lifted from the ``stance`` (4,) feet (4, 2)."""
    remaining = np.array(stance, dtype=bool)
    remaining[leg] = False
    if not remaining.any():
        return -math.inf
    feet = np.asarray(feet_xy, dtype=float)[remaining]
    return float(stability_margin(np.asarray(com_xy, dtype=float), support_polygon(feet)))


def refuse_lift(feet_xy: ArrayLike, stance: ArrayLike, leg: int, com_xy: ArrayLike,
                minimum_margin: float = 0.0) -> bool:
    """Shared control (thesis 3.3): True if lifting ``leg`` now would leave the margin
    below ``minimum_margin`` [m] (default: the centre of mass outside the support)."""
    return margin_after_lift(feet_xy, stance, leg, com_xy) < minimum_margin
