"""An online, statically stable crawl for live driving: automatic or shared control.

The precomputed wave gait of :mod:`.crawl` needs its speed and heading fixed for a whole
run. For driving live (operator console), :class:`OnlineCrawl` plans one step at a time
as a *discontinuous* crawl: the body moves only while all four feet are down (the shift),
then one leg swings while the body stands still (the swing), legs in the lateral sequence
of :data:`.crawl.LATERAL_SEQUENCE`. Every shift ends with the centre of mass inside the
triangle of the three feet that stay down with at least ``minimum_margin`` (the body is
moved towards that triangle's incentre as far as needed), so a lift never starts without
static stability; a lift the measured state would not support is refused
(:func:`.crawl.refuse_lift`, called by the caller with measured feet and centre of mass)
and the shift is repeated.

Two ways to choose footholds:

* **automatic** — a commanded body velocity (speed and heading, world frame; the body
  does not turn): each foot lands half a cycle's travel ahead of its neutral position;
* **shared** — the operator places the front feet (their footholds are the operator's
  targets, e.g. styluses, when the swing ends); each rear foot follows its front foot,
  landing at the front foothold minus the neutral front-to-rear offset; the body follows
  the feet (its neutral position is over the footholds' centroid).

Frames: world x, y horizontal; all positions [m]. The output is the feet relative to the
planned body origin in world-aligned axes (a caller rotates them by the body's yaw).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .crawl import LATERAL_SEQUENCE, LEGS
from .settings import CrawlSettings
from .stability import stability_margin, support_and_margin, support_polygon

__all__ = ["OnlineCrawl", "OnlineCrawlSettings", "shift_for_margin", "swing_point"]

Array = NDArray[np.float64]
#: Extra static margin [m] asked of the body shift after each refused lift.
RETRY_MARGIN = 0.02
FRONT_TO_REAR = {"rear_left": "front_left", "rear_right": "front_right"}


@dataclass(frozen=True)
class OnlineCrawlSettings(CrawlSettings):
    """Timing and limits of the online crawl.

    ``step_height`` and ``minimum_margin`` and their defaults are those of every crawl
    (:class:`.settings.CrawlSettings`, shared with the CLI's wave gait).

    Attributes
    ----------
    step_height : float [m]
        Foot lift at mid-swing.
    minimum_margin : float [m]
        Static margin every shift must reach before a lift.
    shift_time, swing_time : float [s]
        Duration of a body shift (four feet down) and of a swing.
    max_step : float [m]
        Longest foot step on the ground (footholds farther away are shortened).
    idle_distance : float [m]
        With no velocity (automatic) or in shared control, a foot within this distance
        of its target does not step.
    max_reach : float [m]
        Automatic mode: largest distance of a foothold from the leg's neutral foothold
        about the body as it stands during the swing (farther footholds are pulled in:
        a leg asked to land beyond its workspace lands where its clamped joints put it,
        and the body lurches). It also bounds the speed: the body's path stays within
        half of it from the feet.
    """

    shift_time: float = 1.0
    swing_time: float = 1.0
    max_step: float = 0.15
    idle_distance: float = 0.01
    max_reach: float = 0.08


def _smoothstep(fraction: float) -> float:
    x = min(max(fraction, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def swing_point(start: ArrayLike, end: ArrayLike, fraction: float, height: float) -> Array:
    """Foot (3,) [m] at ``fraction`` of a swing from ground point ``start`` to ``end``
    (xy): a cycloid along the ground and a (1 − cos) lift of ``height``, both with zero
    speed at lift-off and touchdown."""
    start, end = np.asarray(start, dtype=float)[:2], np.asarray(end, dtype=float)[:2]
    x = min(max(fraction, 0.0), 1.0)
    along = x - np.sin(2.0 * np.pi * x) / (2.0 * np.pi)
    return np.array([*(start + along * (end - start)),
                     0.5 * height * (1.0 - np.cos(2.0 * np.pi * x))])


def shift_for_margin(body: ArrayLike, com_offset: ArrayLike, support: ArrayLike,
                     minimum_margin: float) -> tuple[Array, float]:
    """Body position (2,) [m] nearest ``body`` on the way to the support's incentre whose
    centre of mass (body + ``com_offset``) has at least ``minimum_margin`` [m] in the
    triangle ``support`` (3, 2); and the margin reached there (the incentre's margin
    when even it falls short)."""
    body = np.asarray(body, dtype=float)
    offset = np.asarray(com_offset, dtype=float)
    triangle = np.asarray(support, dtype=float)[:, :2]
    polygon = support_polygon(triangle)

    def margin(point: Array) -> float:
        return float(stability_margin(point + offset, polygon))

    sides = np.linalg.norm(np.roll(triangle, -1, axis=0) - np.roll(triangle, -2, axis=0),
                           axis=1)
    incentre = sides @ triangle / sides.sum() - offset
    if margin(body) >= minimum_margin:
        return body, margin(body)
    if margin(incentre) < minimum_margin:
        return incentre, margin(incentre)
    low, high = 0.0, 1.0  # bisection on the segment body → incentre
    for _ in range(40):
        middle = 0.5 * (low + high)
        if margin(body + middle * (incentre - body)) >= minimum_margin:
            high = middle
        else:
            low = middle
    point = body + high * (incentre - body)
    return point, margin(point)


class OnlineCrawl:
    """The step-at-a-time crawl (module docstring).

    Parameters
    ----------
    neutral_feet : (4, 3) [m]
        Feet relative to the body origin at rest (:data:`.crawl.LEGS` order; z = minus
        the body height).
    com_offset : (2,) [m]
        Centre-of-mass projection relative to the body origin.
    body : (2,) [m]
        Body origin (world xy) now; the feet start at their neutral footholds.
    settings : OnlineCrawlSettings
    footholds : (4, 2) [m], optional
        Where the feet stand now (world xy); default: their neutral footholds.
    """

    def __init__(self, neutral_feet: ArrayLike, com_offset: ArrayLike, body: ArrayLike,
                 settings: OnlineCrawlSettings | None = None,
                 footholds: ArrayLike | None = None) -> None:
        self.settings = settings or OnlineCrawlSettings()
        self.neutral = np.asarray(neutral_feet, dtype=float)
        self.com_offset = np.asarray(com_offset, dtype=float)[:2]
        self.body = np.asarray(body, dtype=float)[:2].copy()
        self.reference = self.body.copy()  # the body's path without sway (automatic)
        self.footholds = (self.body + self.neutral[:, :2] if footholds is None
                          else np.asarray(footholds, dtype=float)[:, :2].copy())
        self.velocity = np.zeros(2)
        self.shared = False
        self.operator_footholds: dict[str, Array] = {}
        self.sequence_index = 0
        self.phase = "shift"
        self.clock = 0.0
        self.shift_from = self.body.copy()
        self.shift_to = self.body.copy()
        self.swing_from = np.zeros(2)
        self.swing_to = np.zeros(2)
        self.planned_margin = float("nan")
        self.refusal = ""
        self.steps_taken = 0
        self.retries = 0
        self.landed: str | None = None  # the leg that touched down at this shift's start
        self._plan_shift()

    # --- commands ------------------------------------------------------------------
    @property
    def leg(self) -> str:
        """The leg that lifts next (or is swinging)."""
        return LATERAL_SEQUENCE[self.sequence_index]

    @property
    def cycle_time(self) -> float:
        """Time [s] of four shifts and four swings."""
        return 4.0 * (self.settings.shift_time + self.settings.swing_time)

    def command_velocity(self, speed: float, heading: float) -> None:
        """Automatic mode: body speed [m/s] along ``heading`` [rad] (world, CCW from x)."""
        self.velocity = speed * np.array([np.cos(heading), np.sin(heading)])

    def place(self, leg: str, foothold: ArrayLike) -> None:
        """Shared mode: the operator's foothold (world xy [m]) for a front leg."""
        self.operator_footholds[leg] = np.asarray(foothold, dtype=float)[:2].copy()

    # --- planning ------------------------------------------------------------------
    def _target_foothold(self, leg: str) -> Array:
        k = LEGS.index(leg)
        if self.shared:
            if leg in self.operator_footholds:
                target = self.operator_footholds[leg]
            elif leg in FRONT_TO_REAR:
                front = LEGS.index(FRONT_TO_REAR[leg])
                target = self.footholds[front] - (self.neutral[front, :2] - self.neutral[k, :2])
            else:
                target = self.footholds[k]
        else:
            target = self.reference + self.neutral[k, :2] + 0.5 * self.velocity * self.cycle_time
        step = target - self.footholds[k]
        length = float(np.linalg.norm(step))
        if length > self.settings.max_step:
            target = self.footholds[k] + step * (self.settings.max_step / length)
        if not self.shared:  # the operator's footholds are the operator's to choose
            neutral = self.body + self.neutral[k, :2]
            offset = target - neutral
            reach = float(np.linalg.norm(offset))
            if reach > self.settings.max_reach:
                target = neutral + offset * (self.settings.max_reach / reach)
        return target

    def _plan_shift(self, retry: bool = False) -> None:
        """Where the body goes before the next lift (and the margin it will have there);
        a retry after a refused lift only moves towards the support, not along, asking
        :data:`RETRY_MARGIN` more margin each time (up to the support's incentre)."""
        s = self.settings
        self.retries = self.retries + 1 if retry else 0
        required = s.minimum_margin + RETRY_MARGIN * self.retries
        if retry:
            nominal = self.body.copy()
        elif self.shared:
            nominal = self.footholds.mean(axis=0) - self.neutral[:, :2].mean(axis=0)
        else:
            nominal = self.reference + self.velocity * (s.shift_time + s.swing_time)
        support = np.delete(self.footholds, LEGS.index(self.leg), axis=0)
        self.shift_from = self.body.copy()
        self.shift_to, self.planned_margin = shift_for_margin(
            nominal, self.com_offset, support, required)

    # --- time ----------------------------------------------------------------------
    def advance(self, interval: float, lift_allowed: bool = True) -> None:
        """Move on by ``interval`` [s]. ``lift_allowed`` is the caller's measured check
        (e.g. :func:`.crawl.refuse_lift` with the measured feet and centre of mass) for
        lifting :attr:`leg` now; a refused lift repeats the shift."""
        s = self.settings
        self.clock += interval
        if not self.shared and not self.refusal:
            self.reference = self.reference + self.velocity * interval
            # the body's path never runs more than half a reach ahead of where the feet
            # stand: commanded faster than the feet can step, the crawl walks as fast as
            # they can (a path that ran away would pull the body off its support)
            centre = (self.footholds - self.neutral[:, :2]).mean(axis=0)
            lead = self.reference - centre
            distance = float(np.linalg.norm(lead))
            if distance > 0.5 * s.max_reach:
                self.reference = centre + lead * (0.5 * s.max_reach / distance)
        if self.phase == "shift":
            fraction = _smoothstep(self.clock / s.shift_time)
            self.body = self.shift_from + fraction * (self.shift_to - self.shift_from)
            if self.clock < s.shift_time:
                return
            self.clock = 0.0
            k = LEGS.index(self.leg)
            target = self._target_foothold(self.leg)
            standing = self.shared or not np.any(self.velocity)
            if standing and np.linalg.norm(target - self.footholds[k]) < s.idle_distance:
                self._next_leg()
                return
            if self.planned_margin < s.minimum_margin or not lift_allowed:
                self.refusal = (f"lift of {self.leg} refused: static margin "
                                f"{1000 * self.planned_margin:.0f} mm planned"
                                + ("" if lift_allowed else ", negative when measured"))
                self._plan_shift(retry=True)
                return
            self.refusal = ""
            self.phase = "swing"
            self.landed = None
            self.swing_from = self.footholds[k].copy()
            self.swing_to = target
        else:
            if self.shared and self.leg in self.operator_footholds:
                self.swing_to = self._target_foothold(self.leg)  # follow the stylus
            if self.clock < s.swing_time:
                return
            self.clock = 0.0
            self.footholds[LEGS.index(self.leg)] = self.swing_to
            self.steps_taken += 1
            self.landed = self.leg
            self._next_leg()

    def _next_leg(self) -> None:
        self.phase = "shift"
        self.sequence_index = (self.sequence_index + 1) % len(LATERAL_SEQUENCE)
        self._plan_shift()

    # --- output --------------------------------------------------------------------
    def stance(self) -> NDArray[np.bool_]:
        """(4,) True for the legs on the ground."""
        flags = np.ones(len(LEGS), dtype=bool)
        if self.phase == "swing":
            flags[LEGS.index(self.leg)] = False
        return flags

    def feet_relative(self) -> Array:
        """(4, 3) [m] feet relative to the planned body origin (world-aligned axes)."""
        feet = np.empty((len(LEGS), 3))
        feet[:, :2] = self.footholds - self.body
        feet[:, 2] = self.neutral[:, 2]
        if self.phase == "swing":
            k = LEGS.index(self.leg)
            point = swing_point(self.swing_from, self.swing_to,
                                self.clock / self.settings.swing_time, self.settings.step_height)
            feet[k, :2] = point[:2] - self.body
            feet[k, 2] += point[2]
        return feet

    def load_shares(self, unload_time: float = 0.4, load_time: float = 0.08) -> Array:
        """(4,) share in [0, 1] of the load each leg should carry now (for a force-controlled
        stance, :func:`pneumaquad.locomotion.stance_control.track_stance_loads`): 0 for the
        swinging leg; the leg about to lift sheds its load over the last ``unload_time``
        [s] of the shift before it; the leg that just touched down takes load over the
        first ``load_time`` [s] of the next shift."""
        shares = np.ones(len(LEGS))
        k = LEGS.index(self.leg)
        if self.phase == "swing":
            shares[k] = 0.0
            return shares
        remaining = self.settings.shift_time - self.clock
        shares[k] = float(np.clip(remaining / unload_time, 0.0, 1.0))
        if self.landed is not None and self.landed != self.leg:
            shares[LEGS.index(self.landed)] = float(np.clip(self.clock / load_time, 0.0, 1.0))
        return shares

    def margin(self) -> float:
        """Planned static margin [m] now (the feet on the ground, planned body)."""
        return support_and_margin(self.footholds, self.stance(), self.body + self.com_offset)[1]
