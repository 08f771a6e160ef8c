"""Command-line options generated from a settings dataclass and its described fields
(pneumaquad.cli.settings): the `robot walk` options are WalkSettings' fields, with their
defaults, ranges and help, and the command receives the settings object built from them."""

from __future__ import annotations

import inspect
import math
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from pneumaquad.cli.robot import robot_walk
from pneumaquad.cli.settings import option_names, settings_options
from pneumaquad.locomotion.stance_control import StanceControlSettings
from pneumaquad.locomotion.walk_run import (
    WALK_SETTINGS,
    WalkSettingsError,
    check_walk_settings,
)
from pneumaquad.locomotion.walking import WalkSettings


def _app(received: list[Any]) -> typer.Typer:
    app = typer.Typer()

    @app.command()
    @settings_options(WalkSettings, WALK_SETTINGS)
    def walk(settings: WalkSettings, label: str = "x") -> None:
        received.append((settings, label))

    return app


def test_every_described_field_is_an_option_of_robot_walk() -> None:
    parameters = inspect.signature(robot_walk).parameters
    expected = {(s.option or name) for name, s in WALK_SETTINGS.items()}
    expected |= {inner for s in WALK_SETTINGS.values() for inner in s.nested}
    assert expected <= set(parameters)
    assert "settings" not in parameters
    assert parameters["heading"].default == math.degrees(WalkSettings().heading)


def test_defaults_build_the_default_settings() -> None:
    received: list[Any] = []
    result = CliRunner().invoke(_app(received), [])
    assert result.exit_code == 0, result.output
    assert received == [(WalkSettings(), "x")]


def test_options_reach_the_fields() -> None:
    received: list[Any] = []
    result = CliRunner().invoke(_app(received), [
        "--heading", "90", "--margin", "0.05", "--force-gain", "0.02", "--swing-from-body",
        "--no-heading-hold", "--distance", "0.5", "--label", "y"])
    assert result.exit_code == 0, result.output
    settings, label = received[0]
    assert settings == WalkSettings(heading=math.radians(90.0), minimum_margin=0.05,
                                    stance_control=StanceControlSettings(force_gain=0.02),
                                    swing_from_ground=False, heading_hold=False,
                                    distance=0.5)
    assert label == "y"
    CliRunner().invoke(_app(received), ["--no-stance-control"])
    assert received[-1][0].stance_control is None


def test_an_option_out_of_range_names_option_value_and_range() -> None:
    result = CliRunner().invoke(_app([]), ["--duty-factor", "0.5"])
    assert result.exit_code == 2
    assert "0.5 should be at least 0.75 and at most 0.99" in " ".join(
        result.output.replace("│", " ").split())


def test_the_library_checks_the_same_ranges() -> None:
    with pytest.raises(WalkSettingsError, match=r"period: 0\.1 should be at least 0\.5 s") as info:
        check_walk_settings(WalkSettings(period=0.1))
    assert info.value.fields == ("period",)
    with pytest.raises(WalkSettingsError, match="force_gain: 2 should be"):
        check_walk_settings(WalkSettings(stance_control=StanceControlSettings(force_gain=2.0)))
    assert option_names(WALK_SETTINGS, ("minimum_margin", "force_gain")) == (
        "--margin or --force-gain")


def test_options_with_a_unit_take_quantities() -> None:
    """A number option with a unit takes a bare number in that unit or a quantity of the
    same kind: --distance "20 cm", --heading "0.5 rad", --speed "15 mm/s"."""
    received: list[Any] = []
    result = CliRunner().invoke(_app(received), [
        "--distance", "20 cm", "--heading", "0.5 rad", "--speed", "15 mm/s",
        "--period", "8"])
    assert result.exit_code == 0, result.output
    settings, _ = received[0]
    assert settings.distance == pytest.approx(0.2)
    assert settings.heading == pytest.approx(0.5)
    assert settings.speed == pytest.approx(0.015)
    assert settings.period == 8.0


@pytest.mark.parametrize(("arguments", "message"), [
    (["--distance", "20 kg"], "expected a number in m"),
    (["--distance", "2 km"], "should be at least 0.01 m and at most 100 m"),
])
def test_a_quantity_of_another_kind_or_out_of_range_is_refused(arguments, message) -> None:
    result = CliRunner().invoke(_app([]), arguments, terminal_width=200)
    assert result.exit_code == 2
    assert message in " ".join(result.output.replace("│", " ").split())
