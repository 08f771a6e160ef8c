"""The walking command's defaults are the library's: every option of `pneumaquad robot
walk` that sets a WalkSettings or StanceControlSettings field defaults to that field's
default (the CLI states them once more for its help text; this keeps them equal)."""

from __future__ import annotations

import inspect

from pneumaquad.cli.robot import robot_walk
from pneumaquad.locomotion.stance_control import StanceControlSettings
from pneumaquad.locomotion.walking import WalkSettings

#: CLI option -> (settings object, field) where the names differ
RENAMED = {"margin": ("walk", "minimum_margin"), "force_gain": ("stance", "force_gain"),
           "stance_control": None,  # a switch for the whole StanceControlSettings
           "heading": None}  # degrees on the command line, radians in WalkSettings


def test_robot_walk_defaults_equal_the_walk_settings() -> None:
    walk, stance = WalkSettings(), StanceControlSettings()
    settings = {"walk": walk, "stance": stance}
    checked = []
    for name, parameter in inspect.signature(robot_walk).parameters.items():
        target = RENAMED.get(name, ("walk", name))
        if target is None or not hasattr(settings[target[0]], target[1]):
            continue
        expected = getattr(settings[target[0]], target[1])
        assert parameter.default == expected, (
            f"--{name.replace('_', '-')} defaults to {parameter.default!r}, "
            f"{type(settings[target[0]]).__name__}.{target[1]} to {expected!r}")
        checked.append(name)
    assert {"distance", "speed", "duty_factor", "period", "margin", "step_height",
            "lift_fraction", "transfer_gap", "force_gain", "swing_from_ground",
            "heading_hold"} <= set(checked)


def test_the_cli_crawl_and_the_console_crawl_share_their_common_settings() -> None:
    from dataclasses import fields

    from pneumaquad.gait.online import OnlineCrawlSettings
    from pneumaquad.gait.settings import CrawlSettings

    walk, online = WalkSettings(), OnlineCrawlSettings()
    for field in fields(CrawlSettings):
        assert getattr(walk, field.name) == getattr(online, field.name) == field.default, (
            field.name)
    assert issubclass(WalkSettings, CrawlSettings)
    assert issubclass(OnlineCrawlSettings, CrawlSettings)
