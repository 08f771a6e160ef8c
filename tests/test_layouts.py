"""Named layouts are complete and unambiguous: every field of a packed structure is filled
by the code that packs it, names are unique, and the named views of a simulation are the
arrays they name."""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pytest

from pneumaquad.core import layout
from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameters,
    supply_state,
)
from pneumaquad.core.kernel import step_actuators, step_rigs
from pneumaquad.core.physics.chamber import (
    THERMO_ADIABATIC,
    THERMO_HEAT_TRANSFER,
    THERMO_POLYTROPIC,
)
from pneumaquad.core.physics.force import gravity_force
from pneumaquad.core.physics.friction import (
    FRICTION_COULOMB,
    FRICTION_COULOMB_VISCOUS,
    FRICTION_LUGRE,
    FRICTION_STRIBECK_TANH,
    FRICTION_VISCOUS,
)
from pneumaquad.params import load_actuator, load_rig, load_robot
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.model import pack_rig_parameters, rig_initial_state
from pneumaquad.rig.simulate import (
    RIG_COLUMNS,
    RIG_RECORDING,
    RIG_ROW_DTYPE,
    new_rows,
    simulate_rig,
    write_row,
)
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.coupling import JOINT_CONTROL_DTYPE, LINKAGE_DTYPE, SEAL_DTYPE
from pneumaquad.robot.simulation import RobotSimulation


def test_rig_recording_names_are_unique_and_every_column_is_written() -> None:
    fields = [field for field, _ in RIG_RECORDING]
    assert len(set(fields)) == len(fields) and len(set(RIG_COLUMNS)) == len(RIG_COLUMNS)
    assert RIG_ROW_DTYPE.names == tuple(fields)
    setup = load_rig("thesis-rig", ['supply.model="tank"'])  # every column finite
    params = pack_rig_parameters(setup)
    state = rig_initial_state(setup, params)
    records, rows = new_rows(1)
    rows[:] = np.nan  # a field write_row leaves alone stays NaN
    write_row(records, 0, 0.001, 5.5, 0.02, params[0], state[0],
              np.ones(1, layout.ACTUATOR_OUTPUT_DTYPE)[0], supply_state(setup.actuator)[0])
    unwritten = [name for name, value in zip(RIG_COLUMNS, rows[0], strict=True)
                 if not np.isfinite(value)]
    assert unwritten == []
    assert records[0]["command"] == rows[0, RIG_COLUMNS.index("command [V]")] == 5.5
    recording = simulate_rig(setup, np.full(50, 0.02), closed_loop=True).recording
    assert tuple(recording) == RIG_COLUMNS


def test_robot_records_are_filled_from_their_sources() -> None:
    robot = build_robot(load_robot("crr-quadruped"), "fixed")
    simulation = RobotSimulation(robot)
    for dtype in (LINKAGE_DTYPE, SEAL_DTYPE, JOINT_CONTROL_DTYPE):
        assert len(set(dtype.names)) == len(dtype.names)
    for i, joint_type in enumerate(robot.joint_types):
        linkage = robot.linkages[joint_type]
        for field in LINKAGE_DTYPE.names:
            assert simulation.linkage[i][field] == getattr(linkage, field), field
        actuator = robot.actuators[joint_type]
        p = simulation.params[i]  # the joint's own actuator file, by name
        assert p["stroke"] == actuator.cylinder.stroke
        assert p["cap_area"] == actuator.cylinder.cap_area
        assert p["offset_voltage"] == actuator.valve.offset_voltage
        friction = actuator.friction  # Stribeck-tanh: every field set
        seal = simulation.seal[i]
        assert seal["static_force"] == friction.static_force
        assert seal["coulomb_force"] == friction.coulomb_force
        assert seal["stribeck_velocity"] == friction.stribeck_velocity
        assert seal["stribeck_exponent"] == friction.stribeck_exponent
        assert seal["viscous_coefficient"] == friction.viscous_coefficient


def test_named_views_are_the_arrays_they_name() -> None:
    """The bundles handed to the compiled step hold the simulation's own arrays under the
    same names (a swap of two same-shaped arrays in a bundle fails here)."""
    simulation = RobotSimulation(build_robot(load_robot("crr-quadruped"), "fixed"))
    data, model = simulation.data, simulation.model
    sources = {
        "tendon_length": data.ten_length, "tendon_velocity": data.ten_velocity,
        "control": data.ctrl, "tendon_frictionloss": model.tendon_frictionloss,
        "tendon_damping": model.tendon_damping,
        "tendon_ids": simulation.robot.tendon_id, "actuator_ids": simulation.robot.actuator_id,
        "settings": simulation.joint_control,
    }
    bundles = (simulation.mujoco, simulation.cylinders, simulation.actuators,
               simulation.controllers, simulation.trace)
    for bundle in bundles:
        for name, array in bundle._asdict().items():
            source = sources.get(name, getattr(simulation, name, None))
            assert source is not None, name
            assert array is source or (
                array.__array_interface__["data"][0] == source.__array_interface__["data"][0]
                and array.shape == source.shape), f"{type(bundle).__name__}.{name}"


# --- the kernel's records (pneumaquad.core.layout) -------------------------------------
KERNEL_DTYPES = (
    layout.ACTUATOR_PARAMETERS_DTYPE,
    layout.ACTUATOR_STATE_DTYPE,
    layout.ACTUATOR_OUTPUT_DTYPE,
    layout.SUPPLY_DTYPE,
)
ACTUATOR_SETS = ("thesis-rig", "crr-alpha", "crr-beta", "crr-gamma")


def _blank(dtype: np.dtype, count: int = 1) -> np.ndarray:
    """Records with every float NaN and every integer -1 (no enumeration code)."""
    records = np.zeros(count, dtype)
    for name in dtype.names:
        records[name] = np.nan if dtype[name].base.kind == "f" else -1
    return records


def _unfilled(records: np.ndarray) -> list[str]:
    """Fields of ``records`` still holding :func:`_blank`'s markers somewhere."""
    left = []
    for name in records.dtype.names:
        values = records[name]
        blank = np.isnan(values) if values.dtype.kind == "f" else values == -1
        if np.any(blank):
            left.append(name)
    return left


def test_kernel_record_names_are_unique_and_enumerations_are_integers() -> None:
    for dtype in KERNEL_DTYPES:
        assert len(set(dtype.names)) == len(dtype.names)
    p = layout.ACTUATOR_PARAMETERS_DTYPE
    enumerations = ("valve_model", "flow_form", "area_curve", "input_pressure_curve",
                    "friction_model", "thermo_model", "spacer")
    assert [name for name in p.names if p[name].kind == "i"] == list(enumerations)
    assert layout.SUPPLY_DTYPE["model"].kind == "i"
    for side in ("cap", "rod"):
        for half in ("negative", "positive"):
            assert p[f"{side}_polynomial_{half}"].shape == (layout.POLYNOMIAL_COEFFICIENTS,)
    assert set(layout.RIG_PARAMETER_FIELDS) <= set(p.names)
    state = np.zeros(3, layout.ACTUATOR_STATE_DTYPE)
    columns = layout.float_view(state)
    assert columns.shape == (3, len(layout.ACTUATOR_STATE_DTYPE.names))
    columns[1, layout.state_field_index("rod_mass")] = 2.5  # the same memory
    assert state[1]["rod_mass"] == 2.5


@pytest.mark.parametrize("name", ACTUATOR_SETS)
@pytest.mark.parametrize("supply", ["ideal", "tank"])
def test_packing_fills_every_field(name: str, supply: str) -> None:
    """From records of NaN (and -1 for integers), packing a shipped parameter set leaves
    no field unwritten: parameters, rig parameters, state, supply; one kernel step
    writes every output field."""
    overrides = [f'supply.model="{supply}"']
    if supply == "tank":
        overrides += ['supply.tank_volume="1 L"', 'supply.tank_initial_pressure="20 bara"',
                      'supply.tank_temperature="295 K"']
    actuator = load_actuator(name, overrides)
    params = _blank(layout.ACTUATOR_PARAMETERS_DTYPE)
    pack_parameters(actuator, params[0])
    assert _unfilled(params) == []
    assert all(params[0][field] == 0 for field in layout.RIG_PARAMETER_FIELDS)
    state = _blank(layout.ACTUATOR_STATE_DTYPE)
    initial_state(params[0], 0.01, 3e5, 2e5, out=state[0])
    assert _unfilled(state) == []
    shared = supply_state(actuator, out=_blank(layout.SUPPLY_DTYPE))
    assert _unfilled(shared) == []
    outputs = _blank(layout.ACTUATOR_OUTPUT_DTYPE)
    step_actuators(params, state, np.array([6.0]), np.array([0.01]), np.array([0.05]), 1e-3,
                   5, shared, outputs)
    assert _unfilled(outputs) == []
    assert np.all(np.isfinite(layout.float_view(outputs)))


@pytest.mark.parametrize("spacer", [False, True])
def test_rig_packing_fills_every_field(spacer: bool) -> None:
    setup = load_rig("thesis-rig", [f"rig.spacer={str(spacer).lower()}"])
    params = pack_rig_parameters(setup, out=_blank(layout.ACTUATOR_PARAMETERS_DTYPE))
    assert _unfilled(params) == []
    state = rig_initial_state(setup, params)
    outputs = _blank(layout.ACTUATOR_OUTPUT_DTYPE)
    step_rigs(params, state, np.array([6.0]), 1e-3, 5, supply_state(setup.actuator), outputs)
    assert _unfilled(state) == [] and _unfilled(outputs) == []


def _ports(setup: RigSetup):
    valve = setup.actuator.valve
    return (valve.port2, valve.port1) if valve.cap_port == 2 else (valve.port1, valve.port2)


def _expected_parameters(setup: RigSetup) -> dict[str, object]:
    """Each parameter field's source in the validated parameters, stated independently of
    the packing code."""
    a, rig = setup.actuator, setup.rig
    gas, cylinder, valve = a.gas, a.cylinder, a.valve
    simple, friction, thermo = valve.simple, a.friction, a.thermodynamics
    cap_port, rod_port = _ports(setup)
    k, r = gas.heat_capacity_ratio, gas.gas_constant
    polytropic = thermo.polytropic_exponent if thermo.model == "polytropic" else None
    moving_mass = rig.load_mass + cylinder.piston_mass
    return {
        "heat_capacity_ratio": k,
        "gas_constant": r,
        "specific_heat_cp": gas.specific_heat_cp,
        "supply_temperature": gas.supply_temperature,
        "atmospheric_pressure": gas.atmospheric_pressure,
        "critical_pressure_ratio": gas.critical_pressure_ratio,
        "unchoked_flow_constant": pytest.approx(math.sqrt(2 * k / (r * (k - 1))), rel=1e-14),
        "choked_flow_constant": pytest.approx(
            math.sqrt(k / (r * ((k + 1) / 2) ** ((k + 1) / (k - 1)))), rel=1e-14),
        # eq 4.1.5 and 4.1.10: 1/k, and k and k*R/cp + 1 (both n if polytropic); the
        # laminar limit's factors r_l^(1/k) and sqrt(1 - r_l^((k-1)/k))
        "inverse_heat_capacity_ratio": pytest.approx(1 / k, rel=1e-15),
        "flow_coefficient": polytropic if polytropic else k,
        "compression_exponent": polytropic if polytropic else pytest.approx(
            k * r / gas.specific_heat_cp + 1, rel=1e-15),
        "laminar_power": pytest.approx(valve.laminar_pressure_ratio ** (1 / k), rel=1e-15),
        "laminar_root": pytest.approx(
            math.sqrt(1 - valve.laminar_pressure_ratio ** ((k - 1) / k)), rel=1e-10),
        "supply_temperature_root": math.sqrt(gas.supply_temperature),
        "stribeck_flat_velocity": pytest.approx(
            friction.stribeck_velocity * 2 ** (-56 / friction.stribeck_exponent), rel=1e-15),
        "supply_pressure": a.supply.supply_pressure,
        "exhaust_pressure": a.supply.exhaust_pressure,
        "cap_area": cylinder.cap_area,
        "rod_area": cylinder.rod_area,
        "rod_cross_section": cylinder.rod_cross_section,
        "stroke": cylinder.stroke,
        "cap_dead_length": cylinder.cap_dead_length,
        "rod_dead_length": cylinder.rod_dead_length,
        "bore": cylinder.bore,
        "piston_mass": cylinder.piston_mass,
        "valve_model": {"simple": layout.VALVE_SIMPLE,
                        "underlapped": layout.VALVE_UNDERLAPPED}[valve.model],
        "flow_form": {"orifice": layout.FLOW_ORIFICE,
                      "iso6358": layout.FLOW_ISO6358}[valve.flow_form],
        "area_curve": {"polynomial": layout.AREA_POLYNOMIAL,
                       "linear": layout.AREA_LINEAR}[valve.area_curve],
        "input_pressure_curve": {"tanh": layout.INPUT_TANH,
                                 "switched": layout.INPUT_SWITCHED}[valve.input_pressure],
        "offset_voltage": valve.offset_voltage,
        "min_voltage": valve.min_voltage,
        "max_voltage": valve.max_voltage,
        "spool_time_constant": valve.spool_time_constant,
        "laminar_pressure_ratio": valve.laminar_pressure_ratio,
        "valve_area_scale": valve.area_scale,
        "simple_max_area": simple.max_area,
        "simple_leak_area": simple.leak_area,
        "simple_full_scale_voltage": simple.full_scale_voltage,
        "cap_discharge_coefficient": simple.cap_discharge_coefficient,
        "rod_discharge_coefficient": simple.rod_discharge_coefficient,
        "sonic_conductance": simple.sonic_conductance,
        "leak_conductance": simple.leak_conductance,
        "iso_critical_ratio": simple.iso_critical_ratio,
        "cap_polynomial_negative": list(cap_port.area_negative),
        "cap_polynomial_positive": list(cap_port.area_positive),
        "rod_polynomial_negative": list(rod_port.area_negative),
        "rod_polynomial_positive": list(rod_port.area_positive),
        "cap_high_pressure_cutoff": cap_port.high_pressure_cutoff,
        "cap_low_pressure_cutoff": cap_port.low_pressure_cutoff,
        "rod_high_pressure_cutoff": rod_port.high_pressure_cutoff,
        "rod_low_pressure_cutoff": rod_port.low_pressure_cutoff,
        "friction_model": {
            "viscous": FRICTION_VISCOUS, "coulomb": FRICTION_COULOMB,
            "coulomb_viscous": FRICTION_COULOMB_VISCOUS,
            "stribeck_tanh": FRICTION_STRIBECK_TANH, "lugre": FRICTION_LUGRE,
        }[friction.model],
        "static_force": friction.static_force,
        "coulomb_force": friction.coulomb_force,
        "viscous_coefficient": friction.viscous_coefficient,
        "stribeck_velocity": friction.stribeck_velocity,
        "stribeck_exponent": friction.stribeck_exponent,
        "tanh_coefficient": friction.tanh_coefficient,
        "damping_coefficient": friction.damping_coefficient,
        "bristle_stiffness": friction.bristle_stiffness,
        "bristle_damping": friction.bristle_damping,
        "thermo_model": {"adiabatic": THERMO_ADIABATIC, "polytropic": THERMO_POLYTROPIC,
                         "heat_transfer": THERMO_HEAT_TRANSFER}[thermo.model],
        "polytropic_exponent": thermo.polytropic_exponent,
        "heat_transfer_coefficient": thermo.heat_transfer_coefficient,
        "wall_temperature": thermo.wall_temperature,
        "moving_mass": moving_mass,
        "gravity_force": gravity_force(moving_mass, rig.gravity, rig.orientation_angle),
        "end_stop_stiffness": rig.end_stop_stiffness,
        "end_stop_damping": rig.end_stop_damping,
        "spacer": 1 if rig.spacer else 0,
    }


#: Rig configurations in which every two same-shaped parameter fields differ in at least
#: one (checked below), so that a swap of any two in the packing changes a packed value.
SWAP_CONFIGURATIONS = (
    ('cylinder.piston_mass="0.05 kg"', 'valve.min_voltage="0.2 V"',
     'valve.spool_time_constant="3 ms"', 'valve.simple.full_scale_voltage="4.5 V"',
     'thermodynamics.wall_temperature="305 K"', 'thermodynamics.model="heat_transfer"',
     'valve.area_curve="linear"', "rig.spacer=true", 'friction.bristle_damping="150 N*s/m"'),
    ('valve.model="simple"', 'valve.flow_form="iso6358"', 'valve.input_pressure="switched"',
     'friction.model="lugre"', "rig.spacer=true", "valve.cap_port=1"),
    ('friction.model="coulomb_viscous"', 'thermodynamics.model="polytropic"',
     'valve.flow_form="iso6358"', "valve.area_scale=1.5"),
)


def test_every_parameter_field_holds_its_own_source() -> None:
    """Each packed field equals the parameter it names, so a swap of two fields in the
    packing (cap and rod area, say, or two polynomial blocks) fails here."""
    setups = [load_rig("thesis-rig", list(overrides)) for overrides in SWAP_CONFIGURATIONS]
    packed = [pack_rig_parameters(setup)[0] for setup in setups]
    for setup, record in zip(setups, packed, strict=True):
        expected = _expected_parameters(setup)
        assert set(expected) == set(layout.ACTUATOR_PARAMETERS_DTYPE.names)
        for field, value in expected.items():
            if isinstance(value, list):
                assert list(record[field]) == value, field
            else:
                assert record[field] == value, field
    dtype = layout.ACTUATOR_PARAMETERS_DTYPE
    for first, second in combinations(dtype.names, 2):
        if dtype[first].shape == dtype[second].shape:
            assert any(not np.array_equal(r[first], r[second]) for r in packed), (first, second)


def test_state_and_supply_fields_hold_their_sources() -> None:
    setup = load_rig("thesis-rig", ['supply.model="tank"'])
    actuator = setup.actuator
    p = pack_parameters(actuator)
    x, cap, rod, temperature = 0.012, 3.1e5, 2.2e5, 310.0
    state = initial_state(p, x, cap, rod, temperature)
    cylinder, r = actuator.cylinder, actuator.gas.gas_constant
    assert (state["cap_pressure"], state["rod_pressure"], state["position"]) == (cap, rod, x)
    cap_volume = cylinder.cap_area * (x + cylinder.cap_dead_length)
    rod_volume = cylinder.rod_area * (cylinder.stroke - x + cylinder.rod_dead_length)
    assert state["cap_mass"] == pytest.approx(cap * cap_volume / (r * temperature), rel=1e-14)
    assert state["rod_mass"] == pytest.approx(rod * rod_volume / (r * temperature), rel=1e-14)
    tank = supply_state(actuator)[0]
    assert tank["model"] == layout.SUPPLY_TANK
    assert tank["tank_pressure"] == actuator.supply.tank_initial_pressure
    assert tank["tank_volume"] == actuator.supply.tank_volume
    assert tank["tank_temperature"] == actuator.supply.tank_temperature
    assert tank["gas_constant"] == r and tank["drawn_mass"] == 0.0
    assert new_outputs(2).dtype == layout.ACTUATOR_OUTPUT_DTYPE
