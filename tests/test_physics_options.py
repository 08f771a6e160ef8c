"""Optional physics: first-order spool lag and wall heat transfer, against closed forms."""

import math

import numpy as np
import pytest

from conftest import R_AIR, actuator_setup
from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.layout import ACTUATOR_STATE_DTYPE

DT = 1e-3


def _one_actuator(actuator, position, pressure, temperature=None):
    """Parameters, state and outputs of one actuator at rest (arrays of one record)."""
    params = pack_parameter_array([actuator])
    state = np.zeros(1, ACTUATOR_STATE_DTYPE)
    initial_state(params[0], position, pressure, pressure, temperature, out=state[0])
    return params, state, new_outputs(1)


def test_spool_lag_is_first_order() -> None:
    """With spool_time_constant tau, the effective centered voltage after a command step
    follows u·(1 - exp(-t/tau)) exactly (the kernel advances it with the exact update)."""
    tau = 0.008
    actuator = actuator_setup("crr-gamma", f'valve.spool_time_constant="{tau} s"')
    params, state, outputs = _one_actuator(actuator, 0.02, 2e5)
    state[0]["spool_voltage"] = 0.0
    supply = supply_state(actuator)
    command = np.array([7.25])  # centered +2 V
    spools = []
    for _ in range(30):
        step_actuators(
            params, state, command, np.array([0.02]), np.array([0.0]), DT, 5, supply, outputs
        )
        spools.append(state[0]["spool_voltage"])
    times = DT * np.arange(1, 31)
    assert np.allclose(spools, 2.0 * (1.0 - np.exp(-times / tau)), rtol=1e-12, atol=1e-12)


def test_spool_lag_off_follows_command_at_once() -> None:
    actuator = actuator_setup("crr-gamma")
    assert actuator.valve.spool_time_constant == 0.0
    params, state, outputs = _one_actuator(actuator, 0.02, 2e5)
    step_actuators(
        params,
        state,
        np.array([3.0]),
        np.array([0.02]),
        np.array([0.0]),
        DT,
        5,
        supply_state(actuator),
        outputs,
    )
    assert state[0]["spool_voltage"] == pytest.approx(3.0 - 5.25)


def test_heat_transfer_relaxes_closed_chamber_to_wall_temperature() -> None:
    """A closed chamber of fixed volume: m·cv·dT/dt = h·A·(T_wall - T), cv = R/(k-1), so
    T - T_wall decays with tau = m·R / ((k-1)·h·A)."""
    h = 40.0
    actuator = actuator_setup(
        "crr-gamma",
        'thermodynamics.model="heat_transfer"',
        f'thermodynamics.heat_transfer_coefficient="{h} W/(m^2*K)"',
        'thermodynamics.wall_temperature="298 K"',
        'valve.model="simple"',
        'valve.simple.leak_area="0 m^2"',
    )
    position = 0.02
    hot = 360.0
    params, state, outputs = _one_actuator(actuator, position, 3e5, temperature=hot)
    cylinder = actuator.cylinder
    volume = cylinder.cap_area * (position + cylinder.cap_dead_length)
    mass = state[0]["cap_mass"]
    wall = 0.5 * math.pi * cylinder.bore**2 + math.pi * cylinder.bore * volume / cylinder.cap_area
    k = actuator.gas.heat_capacity_ratio
    tau = mass * R_AIR / ((k - 1.0) * h * wall)
    offset = np.array([actuator.valve.offset_voltage])  # closed: zero area at the offset
    steps = round(tau / DT)
    for _ in range(steps):
        step_actuators(
            params,
            state,
            offset,
            np.array([position]),
            np.array([0.0]),
            DT,
            5,
            supply_state(actuator),
            outputs,
        )
    assert state[0]["cap_mass"] == mass  # nothing flowed
    temperature = outputs[0]["cap_temperature"]
    expected = 298.0 + (hot - 298.0) * math.exp(-steps * DT / tau)
    assert temperature == pytest.approx(expected, rel=2e-3)
    assert 298.0 < temperature < hot


def test_valve_parts_switch_separately() -> None:
    """Thesis Table 3's ablations: ``area_curve="linear"`` gives the simple valve's slot area
    with the tanh input pressures kept; ``input_pressure="switched"`` gives plain
    supply/exhaust with the polynomial areas kept."""
    from pneumaquad.core.actuator import pack_parameters
    from pneumaquad.core.physics.valve import input_pressure, simple_valve_area
    from pneumaquad.core.pneumatics import valve_connections
    from pneumaquad.params import load_actuator

    base = load_actuator("thesis-rig")
    linear = load_actuator("thesis-rig", ['valve.area_curve="linear"'])
    switched = load_actuator("thesis-rig", ['valve.input_pressure="switched"'])
    supply = base.supply.supply_pressure
    exhaust = base.supply.exhaust_pressure
    simple = base.valve.simple
    for centered in (-2.0, -0.3, 0.4, 3.0):
        full = valve_connections(pack_parameters(base), centered, supply)
        area_only = valve_connections(pack_parameters(linear), centered, supply)
        pressure_only = valve_connections(pack_parameters(switched), centered, supply)
        slot = simple_valve_area(
            centered, simple.max_area, simple.leak_area, simple.full_scale_voltage
        )
        assert area_only[1] == pytest.approx(simple.cap_discharge_coefficient * slot)
        assert area_only[3] == pytest.approx(simple.rod_discharge_coefficient * slot)
        assert (area_only[0], area_only[2]) == (full[0], full[2])
        cap_source = supply if centered >= 0 else exhaust
        rod_source = exhaust if centered >= 0 else supply
        assert (pressure_only[0], pressure_only[2]) == (cap_source, rod_source)
        assert (pressure_only[1], pressure_only[3]) == (full[1], full[3])
        port = base.valve.port2  # cap_port = 2
        assert full[0] == pytest.approx(
            input_pressure(centered, supply, exhaust, port.high_pressure_cutoff,
                           port.low_pressure_cutoff)
        )


@pytest.mark.parametrize("overrides", [(), ('valve.model="simple"',),
                                       ('valve.flow_form="iso6358"',),
                                       ('valve.area_curve="linear"',)])
def test_valve_area_scale_scales_every_orifice(overrides) -> None:
    """valve.area_scale multiplies both ports' conductances, every valve model and form,
    and leaves the source pressures; the orifice mass flow of a port scales with it."""
    from pneumaquad.core.pneumatics import valve_connections

    base = pack_parameter_array([actuator_setup("crr-gamma", *overrides)])[0]
    double = pack_parameter_array([actuator_setup("crr-gamma", *overrides,
                                                  "valve.area_scale=2.5")])[0]
    for centered in (-2.0, -0.4, 0.0, 0.3, 1.7):
        one = valve_connections(base, centered, 4.5e5)
        two = valve_connections(double, centered, 4.5e5)
        assert (two[0], two[2]) == (one[0], one[2])
        assert two[1] == pytest.approx(2.5 * one[1], rel=1e-15)
        assert two[3] == pytest.approx(2.5 * one[3], rel=1e-15)


def test_robot_sizing_keys_reach_every_cylinder() -> None:
    """actuators.bore and actuators.valve_area_scale of a robot file load every joint's
    actuator with them (and leave the rest of each file)."""
    from pneumaquad.params import load_actuator, load_robot

    robot = load_robot("crr-quadruped", ['actuators.bore="1.25 in"',
                                         "actuators.valve_area_scale=1.5"])
    for joint in ("alpha", "beta", "gamma"):
        name = getattr(robot.actuators, joint)
        actuator = load_actuator(name, robot.actuators.actuator_overrides())
        assert actuator.cylinder.bore == pytest.approx(1.25 * 0.0254)
        assert actuator.valve.area_scale == 1.5
        assert actuator.cylinder.stroke == load_actuator(name).cylinder.stroke
