"""Tests of the parameters package: shipped sets, units, validation, round trip."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest
import tomli_w

from pneumaquad.params import (
    DATA_DIR,
    ActuatorParameters,
    CylinderParameters,
    ParameterError,
    RigSetup,
    apply_overrides,
    list_parameter_sets,
    load_actuator,
    load_rig,
    load_robot,
    parse_quantity,
    resolved_parameters_toml,
)

IN = 0.0254  # thesis in2m, App. B.1.1 l.30
LBF = 4.4482216152605  # N
SHIPPED = ["thesis-rig", "crr-alpha", "crr-beta", "crr-gamma"]


def _raw(name: str = "thesis-rig") -> dict:
    with (DATA_DIR / f"{name}.toml").open("rb") as f:
        return tomllib.load(f)


def _write(tmp_path: Path, raw: dict, name: str = "p.toml") -> Path:
    path = tmp_path / name
    path.write_text(tomli_w.dumps(raw))
    return path


def _rejects(overrides: list[str], *fragments: str, name: str = "thesis-rig") -> ParameterError:
    with pytest.raises(ParameterError) as info:
        load_rig(name, overrides)
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message, message
    return info.value


# --- shipped sets -------------------------------------------------------------------


def test_list_parameter_sets() -> None:
    sets = list_parameter_sets()
    assert sorted(sets) == sorted([*SHIPPED, "crr-quadruped", "crr-quadruped-thesis-pid",
                                   "thesis-rig-thesis-pid"])
    assert all(isinstance(d, str) and d for d in sets.values())


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_actuators_load(name: str) -> None:
    actuator = load_actuator(name)
    assert isinstance(actuator, ActuatorParameters)
    assert actuator.meta.name == name


def test_thesis_rig_loads_as_rig() -> None:
    setup = load_rig("thesis-rig")
    assert isinstance(setup, RigSetup)
    assert setup.rig.orientation_angle == pytest.approx(math.pi / 2)
    assert setup.simulation.substeps == 5
    assert setup.rig.spacer is False


@pytest.mark.parametrize("name", ["crr-alpha", "crr-beta", "crr-gamma"])
def test_crr_sets_are_actuator_only(name: str) -> None:
    raw = _raw(name)
    assert not {"rig", "controller", "simulation"} & raw.keys()
    err = _rejects([], "rig", "missing", name=name)
    assert len(err.problems) == 3


def test_every_shipped_value_has_a_source_comment() -> None:
    for name in SHIPPED:
        for line in (DATA_DIR / f"{name}.toml").read_text().splitlines():
            if "=" in line and not line.startswith(("#", "[", "name", "description", "source")):
                assert "#" in line, f"{name}: {line}"


# --- SI conversion ------------------------------------------------------------------


def test_si_values_thesis_rig() -> None:
    a = load_rig("thesis-rig").actuator
    assert a.gas.atmospheric_pressure == pytest.approx(14.7 * 6894.76, abs=1.0)
    assert a.supply.supply_pressure == pytest.approx(448159.4, abs=1.0)  # (50.3+14.7) psi
    assert a.supply.exhaust_pressure == pytest.approx(15.7 * 6894.76, abs=1.0)
    assert a.cylinder.bore == pytest.approx(0.0269875, rel=1e-12)
    assert a.cylinder.stroke == pytest.approx(1.75 * IN, rel=1e-12)
    assert a.friction.static_force == pytest.approx(20.017, abs=1e-3)
    assert a.friction.coulomb_force == pytest.approx(3 * LBF, rel=1e-9)
    assert a.friction.viscous_coefficient == pytest.approx(0.5 * LBF / IN, rel=1e-9)
    assert a.friction.tanh_coefficient == pytest.approx(40 / IN, rel=1e-9)
    assert a.valve.offset_voltage == 5.25
    assert a.valve.port2.area_positive == (1.32e-8, -1.302e-7, 3.608e-7, -4.33e-8, 1.42e-8)
    assert a.valve.simple.sonic_conductance == pytest.approx(0.25e-3 / 1e5, rel=1e-12)
    assert a.supply.tank_volume == pytest.approx(2e-3, rel=1e-12)
    assert a.supply.tank_initial_pressure == pytest.approx(200e5, rel=1e-12)


def test_cylinder_areas_match_thesis_formulas() -> None:
    cyl = load_actuator("thesis-rig").cylinder
    bore, rod = 1.0625 * IN, 0.375 * IN  # App. B.1.1 l.44-45
    Ap = math.pi * bore**2 / 4 - 0.0045 * 0.0025  # l.51-52
    Arod = math.pi * rod**2 / 4  # l.53
    assert cyl.cap_area == pytest.approx(Ap, rel=1e-12)
    assert cyl.rod_cross_section == pytest.approx(Arod, rel=1e-12)
    assert cyl.rod_area == pytest.approx(Ap - Arod, rel=1e-12)  # l.54


def test_crr_values() -> None:
    alpha, beta = load_actuator("crr-alpha"), load_actuator("crr-beta")
    assert alpha.supply.exhaust_pressure == pytest.approx(24.7 * 6894.76, abs=1.0)
    assert alpha.cylinder.stroke == pytest.approx(3.75 * IN)
    assert beta.cylinder.stroke == pytest.approx(1.75 * IN)
    assert load_actuator("crr-gamma").cylinder == beta.cylinder


def test_parse_quantity_units() -> None:
    atm = parse_quantity("14.7 psia", "pressure", "gas.atmospheric_pressure")
    assert parse_quantity("50.3 psig", "pressure", "p", atm) == pytest.approx(448159.4, abs=1.0)
    assert parse_quantity("65 psia", "pressure", "p") == pytest.approx(448159.4, abs=1.0)
    assert parse_quantity("1 barg", "pressure", "p", 1e5) == pytest.approx(2e5)
    assert parse_quantity("100 kPag", "pressure", "p", 1e5) == pytest.approx(2e5)
    assert parse_quantity("0.1 MPag", "pressure", "p", 1e5) == pytest.approx(2e5)
    assert parse_quantity("5 Pag", "pressure", "p", 1e5) == pytest.approx(1e5 + 5)
    assert parse_quantity("4.5 lbf", "force", "f") == pytest.approx(20.017, abs=1e-3)
    assert parse_quantity("25 degC", "temperature", "t") == pytest.approx(298.15)
    assert parse_quantity("30 deg", "angle", "a") == pytest.approx(math.pi / 6)
    assert parse_quantity("3 in/s", "[length] / [time]", "v") == pytest.approx(3 * IN)


def test_parse_quantity_messages() -> None:
    with pytest.raises(ParameterError) as info:
        parse_quantity("50 kg", "pressure", "supply.supply_pressure")
    assert str(info.value.problems[0]) == (
        "supply.supply_pressure: '50 kg' is a mass; "
        'expected a pressure such as "50.3 psig"'
    )
    for bad, words in [
        ("50.3", "no unit"),
        (50.3, "no unit"),
        ("nan Pa", "not finite"),
        ("inf psi", "not finite"),
        (math.nan, "not finite"),
        ("50 psig", "gauge"),
        ("50 blorps", "could not be parsed"),
    ]:
        with pytest.raises(ParameterError, match=words):
            parse_quantity(bad, "pressure", "k")


def test_programmatic_models_take_si_floats() -> None:
    cyl = CylinderParameters(
        bore=0.027,
        rod_diameter=0.01,
        stroke=0.04,
        cap_dead_length=0.01,
        rod_dead_length=0.01,
        slider_area=0.0,
        piston_mass=0.0,
    )
    assert cyl.cap_area == pytest.approx(math.pi * 0.027**2 / 4)
    assert CylinderParameters(**{**cyl.model_dump(), "bore": "3 cm"}).bore == pytest.approx(0.03)
    with pytest.raises(ValueError, match="finite"):
        CylinderParameters(**{**cyl.model_dump(), "bore": math.inf})


# --- overrides ----------------------------------------------------------------------


def test_overrides_apply() -> None:
    setup = load_rig(
        "thesis-rig",
        [
            "friction.model=lugre",
            "supply.supply_pressure=30 psig",
            'rig.orientation="30 deg"',
            "simulation.substeps=4",
        ],
    )
    assert setup.actuator.friction.model == "lugre"
    assert setup.actuator.supply.supply_pressure == pytest.approx(44.7 * 6894.757, rel=1e-6)
    assert setup.rig.orientation_angle == pytest.approx(math.pi / 6)
    assert setup.simulation.substeps == 4


def test_apply_overrides_does_not_mutate() -> None:
    raw = {"gas": {"heat_capacity_ratio": 1.4}}
    out = apply_overrides(raw, ["gas.heat_capacity_ratio=1.3", "valve.simple.max_area=1 mm^2"])
    assert raw == {"gas": {"heat_capacity_ratio": 1.4}}
    assert out == {"gas": {"heat_capacity_ratio": 1.3}, "valve": {"simple": {"max_area": "1 mm^2"}}}


@pytest.mark.parametrize("override", ["foo", "=3", "gas..k=1"])
def test_rejects_malformed_override(override: str) -> None:
    err = _rejects([override], override, "section.key=value")
    assert err.problems[0].value == override


def test_rejects_override_into_a_value() -> None:
    _rejects(["gas.heat_capacity_ratio.x=1"], "gas.heat_capacity_ratio.x", "non-table")


# --- rejection rules ----------------------------------------------------------------


def test_rejects_unknown_key() -> None:
    _rejects(["cylinder.bor=1 in"], "cylinder.bor", "'1 in'", "not a known key", "'bore'")
    _rejects(["extra.x=1"], "extra", "not a known key")


def test_rejects_missing_key(tmp_path: Path) -> None:
    raw = _raw()
    del raw["cylinder"]["stroke"]
    with pytest.raises(ParameterError, match=r"cylinder\.stroke: missing"):
        load_rig(_write(tmp_path, raw))


def test_rejects_wrong_dimension() -> None:
    _rejects(
        ["supply.supply_pressure=50 kg"],
        "supply.supply_pressure: '50 kg'",
        "is a mass",
        "expected a pressure",
    )


def test_rejects_plain_number_for_dimensional_value() -> None:
    _rejects(["cylinder.stroke=1.75"], "cylinder.stroke: 1.75 has no unit")


@pytest.mark.parametrize("bore", ["0 in", "-1 in"])
def test_rejects_non_positive_bore(bore: str) -> None:
    _rejects([f"cylinder.bore={bore}"], f"cylinder.bore: '{bore}'", "greater than 0")


def test_rejects_rod_not_below_bore() -> None:
    _rejects(["cylinder.rod_diameter=1.0625 in"], "cylinder.rod_diameter: '1.0625 in'", "bore")


def test_rejects_supply_not_above_exhaust() -> None:
    _rejects(
        ["supply.supply_pressure=15.7 psia"],
        "supply.supply_pressure: '15.7 psia'",
        "exhaust_pressure",
    )


def test_rejects_offset_outside_voltage_range() -> None:
    _rejects(["valve.offset_voltage=11 V"], "valve.offset_voltage: '11 V'", "[0 V, 10 V]")


def test_rejects_non_finite() -> None:
    _rejects(["gas.heat_capacity_ratio=nan"], "gas.heat_capacity_ratio: nan", "not finite")
    _rejects(["gas.critical_pressure_ratio=inf"], "gas.critical_pressure_ratio: inf")
    _rejects(["cylinder.stroke=nan in"], "cylinder.stroke: 'nan in'", "not finite")


def test_rejects_wrong_types() -> None:
    _rejects(["rig.spacer=1"], "rig.spacer: 1", "boolean")
    _rejects(["simulation.substeps=true"], "simulation.substeps: True")
    _rejects(["valve.cap_port=true"], "valve.cap_port: True")
    _rejects(['gas.heat_capacity_ratio="1.4"'], "gas.heat_capacity_ratio: '1.4'", "plain number")
    _rejects(["valve.port1.area_positive=[1e-8, 2e-8]"], "valve.port1.area_positive", "5 numbers")
    _rejects(["friction.model=magic"], "friction.model: 'magic'", "'lugre'")
    _rejects(["rig.orientation=sideways"], "rig.orientation: 'sideways'", "vertical_down")


def test_rejects_other_cross_field_rules() -> None:
    _rejects(["friction.coulomb_force=5 lbf"], "friction.coulomb_force: '5 lbf'", "static_force")
    _rejects(["valve.min_voltage=10 V"], "valve.max_voltage", "min_voltage")
    _rejects(["rig.initial_position=2 in"], "rig.initial_position: '2 in'", "stroke")
    _rejects(["thermodynamics.polytropic_exponent=1.5"], "polytropic_exponent: 1.5", "[1, 1.4]")
    _rejects(
        ["supply.model=tank", "supply.tank_initial_pressure=50 psia"],
        "supply.tank_initial_pressure: '50 psia'",
        "at least supply_pressure",
    )


def test_tank_fields_required_only_for_tank(tmp_path: Path) -> None:
    raw = _raw()
    for key in ("tank_volume", "tank_initial_pressure", "tank_temperature"):
        del raw["supply"][key]
    path = _write(tmp_path, raw)
    assert load_rig(path).actuator.supply.tank_volume is None
    with pytest.raises(ParameterError) as info:
        load_rig(path, ["supply.model=tank"])
    assert [p.key for p in info.value.problems] == [
        "supply.tank_volume",
        "supply.tank_initial_pressure",
        "supply.tank_temperature",
    ]


def test_lists_every_problem() -> None:
    err = _rejects(["cylinder.bore=0 in", "supply.supply_pressure=50 kg", "gas.foo=1"])
    assert {p.key for p in err.problems} == {"cylinder.bore", "supply.supply_pressure", "gas.foo"}
    assert str(err).startswith("3 problems")


def test_bad_atmosphere_does_not_cascade() -> None:
    err = _rejects(["gas.atmospheric_pressure=1 psig"], "gas.atmospheric_pressure: '1 psig'")
    assert len(err.problems) == 1


def test_rejects_toml_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[gas]\nheat_capacity_ratio = 1.4\nk = = 3\n")
    with pytest.raises(ParameterError, match="line 3") as info:
        load_rig(path)
    assert str(path) in str(info.value)


def test_rejects_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.toml"
    with pytest.raises(ParameterError, match="does not exist") as info:
        load_rig(path)
    assert str(path) in str(info.value)
    with pytest.raises(ParameterError, match="not a shipped parameter set"):
        load_actuator("no-such-set")


def test_parameter_error_is_value_error() -> None:
    err = _rejects(["cylinder.bore=0 in"])
    assert isinstance(err, ValueError)
    assert err.problems[0].key == "cylinder.bore"
    assert err.problems[0].value == "0 in"


# --- resolved parameters round trip -------------------------------------------------


def test_resolved_rig_round_trip(tmp_path: Path) -> None:
    setup = load_rig("thesis-rig", ["rig.orientation=30 deg", "supply.model=tank"])
    text = resolved_parameters_toml(setup)
    resolved = tomllib.loads(text)
    assert resolved["supply"]["supply_pressure"].startswith("448159.")
    assert resolved["supply"]["supply_pressure"].endswith(" Pa")
    assert resolved["rig"]["initial_rod_pressure"].endswith(" Pa")
    assert resolved["cylinder"]["bore"] == "0.026987499999999998 m"
    again = load_rig(_write(tmp_path, tomllib.loads(text)))
    assert again == setup
    path = tmp_path / "resolved.toml"
    path.write_text(text)
    assert load_rig(path) == setup


@pytest.mark.parametrize("name", SHIPPED)
def test_resolved_actuator_round_trip(tmp_path: Path, name: str) -> None:
    actuator = load_actuator(name)
    path = tmp_path / "resolved.toml"
    path.write_text(resolved_parameters_toml(actuator))
    assert load_actuator(path) == actuator


# --- physically meaningful ranges -------------------------------------------------------


@pytest.mark.parametrize(
    ("override", "fragment"),
    [
        ('cylinder.bore="1e300 in"', "cylinder.bore: '1e300 in' should be greater than 0 m and "
         "at most 10 m"),
        ("gas.heat_capacity_ratio=1e300", "gas.heat_capacity_ratio: 1e+300 should be greater "
         "than 1 and at most 5/3"),
        ("gas.heat_capacity_ratio=1.0", "greater than 1 and at most 5/3"),
        ('rig.gravity="1e300 m/s^2"', "rig.gravity: '1e300 m/s^2' should be at least 0 m/s^2 "
         "and at most 100 m/s^2"),
        ('supply.supply_pressure="2000 bara"', "greater than 0 Pa and at most 100 MPa"),
        ('gas.supply_temperature="2000 K"', "greater than 0 K and less than 2000 K"),
        ('supply.tank_volume="100 m^3"', "greater than 0 m^3 and at most 10 m^3"),
        ('cylinder.piston_mass="2000 kg"', "at least 0 kg and at most 1000 kg"),
        ('valve.max_voltage="1000 V"', "at least -100 V and at most 100 V"),
        ("valve.port2.area_positive=[1.0, 0, 0, 0, 0]", "valve.port2.area_positive[0]"),
        ('friction.static_force="1e6 N"', "at most 100000 N"),
        ('controller.proportional_gain="-300 V/m"', "at least 0 V/m"),
        ('simulation.control_step="10 s"', "at least 1e-06 s and at most 1 s"),
        ("simulation.substeps=100000", "at least 1 and at most 1000"),
        ("thermodynamics.polytropic_exponent=0.5", "at least 1 and at most 5/3"),
        ("simulation.relative_tolerance=2.0", "greater than 0 and less than 1"),
    ],
)
def test_rejects_values_outside_their_physical_range(override: str, fragment: str) -> None:
    err = _rejects([override], fragment)
    assert len(err.problems) == 1


def test_range_ends_are_accepted() -> None:
    setup = load_rig(
        "thesis-rig",
        [
            "gas.heat_capacity_ratio=1.6666666666666667",
            'rig.gravity="100 m/s^2"',
            'cylinder.stroke="10 m"',
            "simulation.substeps=1000",
            'rig.load_mass="1000 kg"',
        ],
    )
    assert setup.actuator.gas.heat_capacity_ratio == pytest.approx(5 / 3)
    assert setup.rig.gravity == 100.0 and setup.actuator.cylinder.stroke == 10.0


def test_ranges_hold_for_models_built_in_python() -> None:
    fields = load_rig("thesis-rig").actuator.cylinder.model_dump()
    with pytest.raises(ValueError, match="greater than 0 m and at most 10 m"):
        CylinderParameters(**(fields | {"bore": 1e300}))
    with pytest.raises(ValueError, match="not finite"):
        CylinderParameters(**(fields | {"stroke": math.inf}))


def test_every_field_states_its_range_in_its_description() -> None:
    properties = CylinderParameters.model_json_schema()["properties"]
    assert properties["bore"]["description"] == (
        "Piston diameter; finite, greater than 0 m and at most 10 m")
    gas = RigSetup.model_json_schema()["$defs"]["GasParameters"]["properties"]
    assert "at most 5/3" in gas["heat_capacity_ratio"]["description"]


@pytest.mark.parametrize(
    ("override", "fragment"),
    [
        ('thorax.diameter="20 m"', "thorax.diameter: '20 m' should be greater than 0 m"),
        ('leg.gamma.upper_limit="400 deg"', "at most π rad (180°)"),
        ("contact.ground_friction=1e9", "at least 0 and at most 10"),
        ('simulation.control_step="0 s"', "at least 1e-06 s"),
        ('environment.ramp_slope="80 deg"', "at most π/3 rad (60°)"),
        ("thorax.color=[2.0, 0.0, 0.0]", "thorax.color[0]"),
        ('linkages.alpha.moving_mass="-1 kg"', "at least 0 kg"),
    ],
)
def test_robot_values_outside_their_range_are_rejected(override: str, fragment: str) -> None:
    with pytest.raises(ParameterError) as info:
        load_robot("crr-quadruped", [override])
    assert fragment in str(info.value), str(info.value)


def test_shipped_robot_set_loads() -> None:
    robot = load_robot("crr-quadruped")
    assert robot.simulation.control_step == 0.001


def test_rejects_file_that_is_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes('[meta]\nname = "Bézier"\n'.encode("latin-1"))
    with pytest.raises(ParameterError) as info:
        load_rig(path)
    message = str(info.value)
    assert "is not UTF-8 text (byte 0xe9 at offset 16)" in message
    assert str(path) in message


def test_shown_parameters_are_rounded_and_still_load(tmp_path):
    from pneumaquad.params import load_rig
    from pneumaquad.params.loader import resolved_parameters_toml

    setup = load_rig("thesis-rig")
    exact = resolved_parameters_toml(setup)
    shown = resolved_parameters_toml(setup, digits=12)
    assert '"0.0020000000000000005 m^3"' in exact  # 2 L converted to m^3
    assert '"0.002 m^3"' in shown and "0.0020000000000000005" not in shown
    assert '"448159.224056 Pa"' in shown
    path = tmp_path / "shown.toml"
    path.write_text(shown, encoding="utf-8")
    again = load_rig(path)
    assert again.actuator.supply.supply_pressure == pytest.approx(
        setup.actuator.supply.supply_pressure, rel=1e-11)


def test_a_layered_file_changes_only_its_keys(tmp_path):
    from pneumaquad.params import ParameterError, load_actuator

    changes = tmp_path / "mine.toml"
    changes.write_text('extends = "crr-gamma"\n[supply]\nsupply_pressure = "45 psig"\n'
                       '[friction]\nstatic_force = "5 lbf"\n', encoding="utf-8")
    deeper = tmp_path / "deeper.toml"  # extends the file beside it
    deeper.write_text('extends = "mine.toml"\n[cylinder]\nbore = "1.25 in"\n',
                      encoding="utf-8")
    full = load_actuator("crr-gamma", ['supply.supply_pressure="45 psig"',
                                       'friction.static_force="5 lbf"',
                                       'cylinder.bore="1.25 in"'])
    assert load_actuator(deeper) == full
    assert load_actuator(changes).cylinder == load_actuator("crr-gamma").cylinder
    loop = tmp_path / "loop.toml"
    loop.write_text('extends = "loop.toml"\n', encoding="utf-8")
    with pytest.raises(ParameterError, match="a loop"):
        load_actuator(loop)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text('extends = "crr-delta"\n', encoding="utf-8")
    with pytest.raises(ParameterError, match=r"extends: 'crr-delta' is not a shipped"):
        load_actuator(unknown)
