"""Fit results written as parameter files the simulator loads."""

from __future__ import annotations

import math

import pytest

from pneumaquad.analysis.fits import check_standard_errors, parameter_name_and_unit
from pneumaquad.identification import FitResult, updates_from_fit, write_parameter_file
from pneumaquad.params import ParameterError, load_rig


def friction_fit() -> FitResult:
    return FitResult(
        name="coulomb-viscous friction",
        parameters={"coulomb_force [N]": 14.2360123456789, "viscous_coefficient [N*s/m]": 69.93},
        standard_errors={"coulomb_force [N]": 0.005, "viscous_coefficient [N*s/m]": 0.04},
        r_squared=0.9998,
        residual_rms=0.12,
        n_points=5423,
        residual_unit="N",
    )


def test_updates_carry_si_units() -> None:
    updates = updates_from_fit(friction_fit(), "friction")
    assert updates == {
        "friction.coulomb_force": "14.2360123456789 N",
        "friction.viscous_coefficient": "69.93 N*s/m",
    }
    exponent = FitResult(
        "x", {"stribeck_exponent [-]": 4.0}, {"stribeck_exponent [-]": 0.1}, math.nan, 0.0, 3
    )
    assert updates_from_fit(exponent, "friction") == {"friction.stribeck_exponent": 4.0}
    assert parameter_name_and_unit("high_pressure_cutoff [V]") == ("high_pressure_cutoff", "V")
    with pytest.raises(ValueError, match="name \\[unit\\]"):
        parameter_name_and_unit("no unit")
    with pytest.raises(KeyError):
        friction_fit().value("static_force")


def test_written_file_loads_and_reproduces_the_fit(tmp_path) -> None:
    fit = friction_fit()
    polynomial = [1.0e-8, -1.2e-7, 3.5e-7, -4.0e-8, 1.5e-8]
    updates = {
        **updates_from_fit(fit, "friction"),
        "friction.static_force": "21.11 N",
        "valve.port2.high_pressure_cutoff": "1.0 V",
        "valve.port2.area_positive": polynomial,
    }
    path = write_parameter_file("thesis-rig", updates, tmp_path / "out" / "fitted.toml", [fit])
    text = path.read_text(encoding="utf-8")
    assert text.startswith("# Identified by pneumaquad.identification")
    assert "coulomb-viscous friction" in text and "base parameter set: thesis-rig" in text
    setup = load_rig(path)
    friction = setup.actuator.friction
    assert friction.coulomb_force == pytest.approx(fit.value("coulomb_force"), rel=1e-12)
    assert friction.viscous_coefficient == pytest.approx(69.93, rel=1e-12)
    assert friction.static_force == pytest.approx(21.11, rel=1e-12)
    assert setup.actuator.valve.port2.high_pressure_cutoff == 1.0
    assert list(setup.actuator.valve.port2.area_positive) == polynomial
    # everything else is the base set's
    base = load_rig("thesis-rig")
    assert setup.actuator.cylinder == base.actuator.cylinder
    assert setup.rig == base.rig
    assert friction.stribeck_velocity == pytest.approx(base.actuator.friction.stribeck_velocity)
    # a fitted file can be the base of the next fit, with overrides
    again = write_parameter_file(
        path,
        {"friction.coulomb_force": "10 N"},
        tmp_path / "again.toml",
        overrides=["rig.load_mass=0.5 kg"],
    )
    assert load_rig(again).rig.load_mass == 0.5


def test_invalid_result_is_refused_and_not_written(tmp_path) -> None:
    target = tmp_path / "bad.toml"
    with pytest.raises(ParameterError, match="coulomb_force"):
        write_parameter_file("thesis-rig", {"friction.coulomb_force": "50 N"}, target)
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ParameterError, match="no-such-set"):
        write_parameter_file("no-such-set", {}, target)


def test_check_standard_errors_flags_undetermined_parameters() -> None:
    fit = FitResult(
        name="coulomb-viscous friction",
        parameters={"coulomb_force [N]": 13.0, "viscous_coefficient [N*s/m]": 2.0},
        standard_errors={"coulomb_force [N]": 0.1, "viscous_coefficient [N*s/m]": 0.9},
        r_squared=0.99,
        residual_rms=0.2,
        n_points=100,
    )
    checked = check_standard_errors(fit)
    assert checked.failed and len(checked.problems) == 1
    assert "viscous_coefficient" in checked.problems[0]
    assert check_standard_errors(fit, max_relative_error=0.5) is fit
    undetermined = FitResult("x", {"a [N]": 1.0}, {"a [N]": float("inf")}, 0.0, 1.0, 3)
    assert check_standard_errors(undetermined).failed
