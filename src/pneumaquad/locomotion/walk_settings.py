"""The settings of a judged walk: one light module the command line reads.

:class:`WalkSettings` (the crawl's settings and the walk's length, turn and speed),
:class:`StanceControlSettings` (the force-controlled stance) and :data:`WALK_SETTINGS`
(what each field sets and the values it takes, from which the ``robot walk`` options are
built) import nothing heavier than the parameter schema, so that ``pneumaquad --help``
does not load MuJoCo or compile anything. :mod:`.walking`, :mod:`.stance_control` and
:mod:`.walk_run` use them from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pneumaquad.gait.settings import CrawlSettings
from pneumaquad.params.fields import Bounds
from pneumaquad.params.settings import Setting, check_settings

__all__ = ["GAIT_FIELDS", "REACH_FIELDS", "TURN_RATE", "TURN_TOLERANCE", "WALK_SETTINGS",
           "StanceControlSettings", "WalkSettings", "WalkSettingsError",
           "check_walk_settings"]

#: Yaw rate [rad/s] of a turn in place when none is given: 2°/s, a 14° turn of the feet
#: about the body per stance of the default 8 s cycle (about the default stride's 0.144 m
#: at the feet's 0.5 m from the body's centre).
TURN_RATE = math.radians(2.0)
#: Largest error of a turn in place [rad] (yaw at the end of the run, from the yaw the
#: robot lay in) that succeeds.
TURN_TOLERANCE = math.radians(5.0)


@dataclass(frozen=True)
class StanceControlSettings:
    """Settings of the force-controlled stance.

    Attributes
    ----------
    force_gain : float [V/N]
        Valve voltage per newton of cylinder force error (force tracking gain k_F). The
        position loop then acts as a spring of stiffness·Kp / k_F: with beta's Kp =
        150 V/m, 0.015 V/N and the stiffness factor 2, 20 N/mm at the piston. 0.015 V/N
        from walks on the three terrains (docs/robot.md); 0.01 V/N rocked more on the ramp.
    rise : float
        Cycle fraction over which a leg's load share rises after touchdown.
    fall : float
        Cycle fraction over which it falls before lift-off.
    """

    force_gain: float = 0.015
    rise: float = 0.01
    fall: float = 0.04
    stiffness: float = 2.0

    def __post_init__(self) -> None:
        if not self.force_gain > 0.0:
            raise ValueError(f"force_gain must be > 0 V/N, got {self.force_gain!r}")
        if not (0.0 < self.rise < 0.5 and 0.0 < self.fall < 0.5):
            raise ValueError(f"rise and fall must be cycle fractions in (0, 0.5), got "
                             f"{self.rise!r} and {self.fall!r}")


@dataclass(frozen=True)
class WalkSettings(CrawlSettings):
    """Gait settings: step height [m] and planned minimum static margin [m] (with their
    defaults from :class:`pneumaquad.gait.settings.CrawlSettings`, which the console's
    online crawl shares), speed [m/s], heading [rad], duty factor, period [s], distance
    to walk [m], the swing's share of pure lift and lowering and the four-legged transfer
    gap before each front lift-off (cycle fractions,
    :class:`pneumaquad.gait.crawl.CrawlGait`), the force-controlled stance (None: plain
    position control of the planned joint angles) and the swing and heading corrections.
    Defaults: the settings that walked every terrain in our measurements (docs/robot.md)."""

    speed: float = 0.02
    heading: float = 0.0
    duty_factor: float = 0.9
    period: float = 8.0
    distance: float = 1.0
    lift_fraction: float = 0.25
    transfer_gap: float = 0.04
    stance_control: StanceControlSettings | None = field(
        default_factory=StanceControlSettings)
    swing_from_ground: bool = True
    heading_hold: bool = True
    body_placement: bool = True
    turn: float = 0.0
    yaw_rate: float = 0.0

    @property
    def turning_in_place(self) -> bool:
        """A turn in place (``turn`` [rad] not 0): no travel, speed and distance unused."""
        return self.turn != 0.0

    def duration(self) -> float:
        """Walking time [s]: the whole number of gait cycles (at least one) whose planned
        body travel is nearest to the distance. A walk ends as it began, on four feet
        with the body swayed to the same side, within half a cycle's travel
        (speed·T/2, less than a stride) of the distance. A turn in place: the whole
        number of cycles at ``|yaw_rate|`` (:data:`TURN_RATE` if 0) nearest to the turn,
        the rate then adjusted so that they turn exactly by it."""
        if self.turning_in_place:
            rate = abs(self.yaw_rate) or TURN_RATE
            cycles = max(1, round(abs(self.turn) / (rate * self.period)))
        else:
            cycles = max(1, round(self.distance / (self.speed * self.period)))
        return cycles * self.period

    def body_yaw_rate(self) -> float:
        """Planned body yaw rate [rad/s] (counter-clockwise): the turn over the walk's
        duration when turning in place, else ``yaw_rate`` (an arc; 0 straight)."""
        return self.turn / self.duration() if self.turning_in_place else self.yaw_rate

    def body_speed(self) -> float:
        """Planned body speed [m/s]: 0 when turning in place, else ``speed``."""
        return 0.0 if self.turning_in_place else self.speed


def _closed(lower: float, upper: float, unit: str = "") -> Bounds:
    return Bounds(lower, upper, unit, lower_inclusive=True)


#: What each field of :class:`.walking.WalkSettings` sets and the values it takes; the
#: ``robot walk`` options are built from these and the dataclass's defaults.
WALK_SETTINGS: dict[str, Setting] = {
    "distance": Setting("Distance to walk", _closed(0.01, 100.0, "m")),
    "speed": Setting("Body speed", _closed(0.001, 1.0, "m/s")),
    "heading": Setting("Walking direction, counter-clockwise from forward",
                       _closed(-360.0, 360.0, "deg"), scale=math.pi / 180.0),
    "duty_factor": Setting("Stance fraction of the gait cycle", _closed(0.75, 0.99)),
    "period": Setting("Gait cycle", _closed(0.5, 600.0, "s")),
    "minimum_margin": Setting("Planned static margin", _closed(0.0, 1.0, "m"),
                              option="margin"),
    "step_height": Setting("Foot lift at mid-swing", _closed(0.0, 0.5, "m")),
    "lift_fraction": Setting("Share of the swing, at each end, spent only lifting or "
                             "lowering the foot", _closed(0.0, 0.49)),
    "transfer_gap": Setting("Cycle fraction with four feet down between a rear touchdown "
                            "and the front lift-off (load transfer)", _closed(0.0, 0.5)),
    "stance_control": Setting(
        "Force-controlled stance: each stance leg's cylinders track the load statics gives "
        "it (locomotion.stance_control); off: plain position control",
        nested={"force_gain": Setting("Force tracking gain of the stance cylinders",
                                      _closed(1e-6, 1.0, "V/N"))}),
    "swing_from_ground": Setting("Swing height above the ground at lift-off "
                                 "(locomotion.swing_control), or relative to the body as "
                                 "planned", off_option="swing-from-body"),
    "heading_hold": Setting("Hold the initial heading (locomotion.heading_control)"),
    "body_placement": Setting("Place the body uphill on a slope and hold it in place when "
                              "turning in place (locomotion.body_placement)"),
    "turn": Setting("Turn in place by this angle, counter-clockwise (0: walk the distance)",
                    _closed(-720.0, 720.0, "deg"), scale=math.pi / 180.0),
    "yaw_rate": Setting("Body yaw rate, counter-clockwise: walking, an arc; turning in "
                        "place, its rate (0 there: 2 deg/s)",
                        _closed(-10.0, 10.0, "deg/s"), scale=math.pi / 180.0),
}

#: The settings the gait's own checks (:class:`pneumaquad.gait.crawl.CrawlGait`,
#: :func:`pneumaquad.gait.crawl.sway_for_margin`) weigh against each other.
GAIT_FIELDS = ("duty_factor", "lift_fraction", "transfer_gap", "minimum_margin")
#: The settings that decide whether the legs reach the plan (:mod:`.reach`).
REACH_FIELDS = ("heading", "speed", "period", "step_height")


class WalkSettingsError(ValueError):
    """Walk settings out of range, or that the gait cannot meet.

    Attributes
    ----------
    fields : tuple of str
        The :class:`.walking.WalkSettings` fields concerned.
    """

    def __init__(self, message: str, fields: tuple[str, ...]) -> None:
        super().__init__(message)
        self.fields = fields


def check_walk_settings(settings: WalkSettings) -> None:
    """Check every field of ``settings`` against its range in :data:`WALK_SETTINGS`.

    Raises
    ------
    WalkSettingsError
        Naming the field, the value and the range.
    """
    for name, description in WALK_SETTINGS.items():
        try:
            check_settings(settings, {name: description})
        except ValueError as error:
            raise WalkSettingsError(str(error), (name,)) from None
