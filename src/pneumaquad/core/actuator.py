"""Object layer over the kernels: packing parameter objects into the named records of
:mod:`pneumaquad.core.layout`, and initial actuator and supply states."""

import math
from collections.abc import Sequence

import numpy as np

from pneumaquad.core import layout
from pneumaquad.core.physics.chamber import (
    THERMO_ADIABATIC,
    THERMO_HEAT_TRANSFER,
    THERMO_POLYTROPIC,
    chamber_volume_cap,
    chamber_volume_rod,
)
from pneumaquad.core.physics.friction import (
    FRICTION_COULOMB,
    FRICTION_COULOMB_VISCOUS,
    FRICTION_LUGRE,
    FRICTION_STRIBECK_TANH,
    FRICTION_VISCOUS,
    stribeck_flat_velocity,
)
from pneumaquad.core.physics.orifice import laminar_limit, orifice_coefficients
from pneumaquad.core.pneumatics import FlowConstants, derived_flow_constants
from pneumaquad.params.schema import (
    ActuatorParameters,
    ValveParameters,
    ValvePortParameters,
)

FRICTION_CODES = {
    "viscous": FRICTION_VISCOUS,
    "coulomb": FRICTION_COULOMB,
    "coulomb_viscous": FRICTION_COULOMB_VISCOUS,
    "stribeck_tanh": FRICTION_STRIBECK_TANH,
    "lugre": FRICTION_LUGRE,
}
THERMO_CODES = {
    "adiabatic": THERMO_ADIABATIC,
    "polytropic": THERMO_POLYTROPIC,
    "heat_transfer": THERMO_HEAT_TRANSFER,
}
VALVE_CODES = {"simple": layout.VALVE_SIMPLE, "underlapped": layout.VALVE_UNDERLAPPED}
AREA_CURVE_CODES = {"polynomial": layout.AREA_POLYNOMIAL, "linear": layout.AREA_LINEAR}
INPUT_PRESSURE_CODES = {"tanh": layout.INPUT_TANH, "switched": layout.INPUT_SWITCHED}
FLOW_CODES = {"orifice": layout.FLOW_ORIFICE, "iso6358": layout.FLOW_ISO6358}


def chamber_ports(valve: ValveParameters) -> tuple[ValvePortParameters, ValvePortParameters]:
    """The underlapped valve's (cap-side port, rod-side port), per ``valve.cap_port``."""
    if valve.cap_port == 2:
        return valve.port2, valve.port1
    return valve.port1, valve.port2


def new_parameters(count: int | None = None) -> np.ndarray | np.void:
    """Zeroed parameter records (:data:`~pneumaquad.core.layout.ACTUATOR_PARAMETERS_DTYPE`):
    one record, or an array of ``count``."""
    if count is None:
        return np.zeros(1, layout.ACTUATOR_PARAMETERS_DTYPE)[0]
    return np.zeros(count, layout.ACTUATOR_PARAMETERS_DTYPE)


def pack_parameters(actuator: ActuatorParameters, out: np.void | None = None) -> np.void:
    """Pack one actuator's parameters into a kernel record, every field by name (SI).

    Parameters
    ----------
    actuator : ActuatorParameters
        Validated parameters.
    out : numpy.void, optional
        Record of :data:`~pneumaquad.core.layout.ACTUATOR_PARAMETERS_DTYPE` to fill (an
        element of a parameter array); a new one by default.

    Returns
    -------
    numpy.void
        The filled record. The rig fields
        (:data:`~pneumaquad.core.layout.RIG_PARAMETER_FIELDS`) are zero; set them with
        :func:`pneumaquad.rig.model.pack_rig_parameters`.
    """
    gas, supply, cylinder = actuator.gas, actuator.supply, actuator.cylinder
    valve, friction, thermo = actuator.valve, actuator.friction, actuator.thermodynamics
    record = new_parameters() if out is None else out
    c1, c2 = orifice_coefficients(gas.heat_capacity_ratio, gas.gas_constant)
    record["heat_capacity_ratio"] = gas.heat_capacity_ratio
    record["gas_constant"] = gas.gas_constant
    record["specific_heat_cp"] = gas.specific_heat_cp
    record["supply_temperature"] = gas.supply_temperature
    record["atmospheric_pressure"] = gas.atmospheric_pressure
    record["critical_pressure_ratio"] = gas.critical_pressure_ratio
    record["unchoked_flow_constant"] = c1
    record["choked_flow_constant"] = c2
    record["supply_pressure"] = supply.supply_pressure
    record["exhaust_pressure"] = supply.exhaust_pressure
    record["cap_area"] = cylinder.cap_area
    record["rod_area"] = cylinder.rod_area
    record["rod_cross_section"] = cylinder.rod_cross_section
    record["stroke"] = cylinder.stroke
    record["cap_dead_length"] = cylinder.cap_dead_length
    record["rod_dead_length"] = cylinder.rod_dead_length
    record["bore"] = cylinder.bore
    record["piston_mass"] = cylinder.piston_mass
    record["valve_model"] = VALVE_CODES[valve.model]
    record["flow_form"] = FLOW_CODES[valve.flow_form]
    record["area_curve"] = AREA_CURVE_CODES[valve.area_curve]
    record["input_pressure_curve"] = INPUT_PRESSURE_CODES[valve.input_pressure]
    record["offset_voltage"] = valve.offset_voltage
    record["min_voltage"] = valve.min_voltage
    record["max_voltage"] = valve.max_voltage
    record["spool_time_constant"] = valve.spool_time_constant
    record["laminar_pressure_ratio"] = valve.laminar_pressure_ratio
    record["valve_area_scale"] = valve.area_scale
    simple = valve.simple
    record["simple_max_area"] = simple.max_area
    record["simple_leak_area"] = simple.leak_area
    record["simple_full_scale_voltage"] = simple.full_scale_voltage
    record["cap_discharge_coefficient"] = simple.cap_discharge_coefficient
    record["rod_discharge_coefficient"] = simple.rod_discharge_coefficient
    record["sonic_conductance"] = simple.sonic_conductance
    record["leak_conductance"] = simple.leak_conductance
    record["iso_critical_ratio"] = simple.iso_critical_ratio
    cap_port, rod_port = chamber_ports(valve)
    record["cap_polynomial_negative"] = cap_port.area_negative
    record["cap_polynomial_positive"] = cap_port.area_positive
    record["rod_polynomial_negative"] = rod_port.area_negative
    record["rod_polynomial_positive"] = rod_port.area_positive
    record["cap_high_pressure_cutoff"] = cap_port.high_pressure_cutoff
    record["cap_low_pressure_cutoff"] = cap_port.low_pressure_cutoff
    record["rod_high_pressure_cutoff"] = rod_port.high_pressure_cutoff
    record["rod_low_pressure_cutoff"] = rod_port.low_pressure_cutoff
    record["friction_model"] = FRICTION_CODES[friction.model]
    record["static_force"] = friction.static_force
    record["coulomb_force"] = friction.coulomb_force
    record["viscous_coefficient"] = friction.viscous_coefficient
    record["stribeck_velocity"] = friction.stribeck_velocity
    record["stribeck_exponent"] = friction.stribeck_exponent
    record["stribeck_flat_velocity"] = stribeck_flat_velocity(
        friction.stribeck_velocity, friction.stribeck_exponent)
    record["tanh_coefficient"] = friction.tanh_coefficient
    record["damping_coefficient"] = friction.damping_coefficient
    record["bristle_stiffness"] = friction.bristle_stiffness
    record["bristle_damping"] = friction.bristle_damping
    record["thermo_model"] = THERMO_CODES[thermo.model]
    record["polytropic_exponent"] = thermo.polytropic_exponent
    record["heat_transfer_coefficient"] = thermo.heat_transfer_coefficient
    record["wall_temperature"] = thermo.wall_temperature
    constants = derived_flow_constants(
        gas.heat_capacity_ratio, gas.gas_constant, gas.specific_heat_cp,
        record["thermo_model"], thermo.polytropic_exponent)
    for field, value in zip(FlowConstants._fields, constants, strict=True):
        record[field] = value
    record["laminar_power"], record["laminar_root"] = laminar_limit(
        valve.laminar_pressure_ratio, constants.inverse_heat_capacity_ratio)
    record["supply_temperature_root"] = math.sqrt(gas.supply_temperature)
    for field in layout.RIG_PARAMETER_FIELDS:  # not a rig: pack_rig_parameters sets them
        record[field] = 0
    return record


def pack_parameter_array(actuators: Sequence[ActuatorParameters]) -> np.ndarray:
    """Parameter records of several actuators, in order: an (N,) array of
    :data:`~pneumaquad.core.layout.ACTUATOR_PARAMETERS_DTYPE` (see :func:`pack_parameters`)."""
    params = new_parameters(len(actuators))
    for index, actuator in enumerate(actuators):
        pack_parameters(actuator, params[index])
    return params


def initial_state(
    p: np.void,
    position: float,
    cap_pressure: float,
    rod_pressure: float,
    temperature: float | None = None,
    out: np.void | None = None,
) -> np.void:
    """Kernel state for an actuator at rest with given chamber pressures.

    Parameters
    ----------
    p : numpy.void
        Packed parameters of the actuator (:func:`pack_parameters`).
    position : float
        Piston extension [m].
    cap_pressure, rod_pressure : float
        Absolute chamber pressures [Pa].
    temperature : float, optional
        Gas temperature [K]; the supply temperature by default.
    out : numpy.void, optional
        Record of :data:`~pneumaquad.core.layout.ACTUATOR_STATE_DTYPE` to fill (an element
        of a state array); a new one by default.

    Returns
    -------
    numpy.void
        State record with masses from the ideal gas law (eq 4.1.7), at rest (zero
        velocity, spool at the centre, no bristle deflection, no air consumed yet).
    """
    gas_temperature = p["supply_temperature"] if temperature is None else temperature
    state = np.zeros(1, layout.ACTUATOR_STATE_DTYPE)[0] if out is None else out
    cap_volume = chamber_volume_cap(position, p["cap_area"], p["cap_dead_length"])
    rod_volume = chamber_volume_rod(
        position, p["stroke"], p["rod_area"], p["rod_dead_length"]
    )
    gas_constant = p["gas_constant"]
    state["cap_pressure"] = cap_pressure
    state["rod_pressure"] = rod_pressure
    state["cap_mass"] = cap_pressure * cap_volume / (gas_constant * gas_temperature)
    state["rod_mass"] = rod_pressure * rod_volume / (gas_constant * gas_temperature)
    state["spool_voltage"] = 0.0
    state["bristle_deflection"] = 0.0
    state["air_consumed"] = 0.0
    state["position"] = position
    state["velocity"] = 0.0
    return state


def new_outputs(count: int) -> np.ndarray:
    """Zeroed kernel outputs of ``count`` actuators
    (:data:`~pneumaquad.core.layout.ACTUATOR_OUTPUT_DTYPE`)."""
    return np.zeros(count, layout.ACTUATOR_OUTPUT_DTYPE)


def supply_state(actuator: ActuatorParameters, out: np.ndarray | None = None) -> np.ndarray:
    """Shared supply state for the kernels: ideal, or a tank at its initial pressure.

    Returns an array of one :data:`~pneumaquad.core.layout.SUPPLY_DTYPE` record (``out``,
    filled, when given). An ideal supply has zero tank fields; nothing is drawn yet.
    """
    supply = np.zeros(1, layout.SUPPLY_DTYPE) if out is None else out
    record = supply[0]
    record["gas_constant"] = actuator.gas.gas_constant
    record["drawn_mass"] = 0.0
    if actuator.supply.model == "tank":
        record["model"] = layout.SUPPLY_TANK
        record["tank_pressure"] = actuator.supply.tank_initial_pressure
        record["tank_volume"] = actuator.supply.tank_volume
        record["tank_temperature"] = actuator.supply.tank_temperature
    else:
        record["model"] = layout.SUPPLY_IDEAL
        record["tank_pressure"] = 0.0
        record["tank_volume"] = 0.0
        record["tank_temperature"] = 0.0
    return supply
