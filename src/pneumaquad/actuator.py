"""Object layer over the kernels: packing parameter objects and initial actuator states."""

from collections.abc import Sequence

import numpy as np

from pneumaquad import layout as L
from pneumaquad.params.schema import ActuatorParameters
from pneumaquad.physics.chamber import (
    THERMO_ADIABATIC,
    THERMO_HEAT_TRANSFER,
    THERMO_POLYTROPIC,
    chamber_volume_cap,
    chamber_volume_rod,
)
from pneumaquad.physics.friction import (
    FRICTION_COULOMB,
    FRICTION_COULOMB_VISCOUS,
    FRICTION_LUGRE,
    FRICTION_STRIBECK_TANH,
    FRICTION_VISCOUS,
)
from pneumaquad.physics.orifice import orifice_coefficients

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
VALVE_CODES = {"simple": L.VALVE_SIMPLE, "underlapped": L.VALVE_UNDERLAPPED}
FLOW_CODES = {"orifice": L.FLOW_ORIFICE, "iso6358": L.FLOW_ISO6358}


def pack_parameters(actuator: ActuatorParameters) -> np.ndarray:
    """Pack one actuator's parameters into a kernel row (SI, see :mod:`pneumaquad.layout`).

    Parameters
    ----------
    actuator : ActuatorParameters
        Validated parameters.

    Returns
    -------
    numpy.ndarray
        Row of length N_PARAMETERS. Rig-only columns are zero; set them with
        :func:`pneumaquad.rig.model.pack_rig_parameters`.
    """
    gas, supply, cylinder = actuator.gas, actuator.supply, actuator.cylinder
    valve, friction, thermo = actuator.valve, actuator.friction, actuator.thermodynamics
    row = np.zeros(L.N_PARAMETERS)
    c1, c2 = orifice_coefficients(gas.heat_capacity_ratio, gas.gas_constant)
    row[L.P_K] = gas.heat_capacity_ratio
    row[L.P_R] = gas.gas_constant
    row[L.P_CP] = gas.specific_heat_cp
    row[L.P_TS] = gas.supply_temperature
    row[L.P_PATM] = gas.atmospheric_pressure
    row[L.P_CRITICAL] = gas.critical_pressure_ratio
    row[L.P_C1] = c1
    row[L.P_C2] = c2
    row[L.P_PS] = supply.supply_pressure
    row[L.P_PE] = supply.exhaust_pressure
    row[L.P_CAP_AREA] = cylinder.cap_area
    row[L.P_ROD_AREA] = cylinder.rod_area
    row[L.P_ROD_SECTION] = cylinder.rod_cross_section
    row[L.P_STROKE] = cylinder.stroke
    row[L.P_CAP_DEAD] = cylinder.cap_dead_length
    row[L.P_ROD_DEAD] = cylinder.rod_dead_length
    row[L.P_BORE] = cylinder.bore
    row[L.P_PISTON_MASS] = cylinder.piston_mass
    row[L.P_VALVE_MODEL] = VALVE_CODES[valve.model]
    row[L.P_FLOW_FORM] = FLOW_CODES[valve.flow_form]
    row[L.P_OFFSET] = valve.offset_voltage
    row[L.P_UMIN] = valve.min_voltage
    row[L.P_UMAX] = valve.max_voltage
    row[L.P_SPOOL_TAU] = valve.spool_time_constant
    row[L.P_LAMINAR] = valve.laminar_pressure_ratio
    simple = valve.simple
    row[L.P_SIMPLE_MAX_AREA] = simple.max_area
    row[L.P_SIMPLE_LEAK_AREA] = simple.leak_area
    row[L.P_SIMPLE_FULL_SCALE] = simple.full_scale_voltage
    row[L.P_CD_CAP] = simple.cap_discharge_coefficient
    row[L.P_CD_ROD] = simple.rod_discharge_coefficient
    row[L.P_ISO_CONDUCTANCE] = simple.sonic_conductance
    row[L.P_ISO_LEAK_CONDUCTANCE] = simple.leak_conductance
    row[L.P_ISO_B] = simple.iso_critical_ratio
    cap_port, rod_port = (valve.port2, valve.port1) if valve.cap_port == 2 else (
        valve.port1, valve.port2)
    row[L.P_CAP_POLY_NEG : L.P_CAP_POLY_NEG + 5] = cap_port.area_negative
    row[L.P_CAP_POLY_POS : L.P_CAP_POLY_POS + 5] = cap_port.area_positive
    row[L.P_ROD_POLY_NEG : L.P_ROD_POLY_NEG + 5] = rod_port.area_negative
    row[L.P_ROD_POLY_POS : L.P_ROD_POLY_POS + 5] = rod_port.area_positive
    row[L.P_CAP_HIGH_CUTOFF] = cap_port.high_pressure_cutoff
    row[L.P_CAP_LOW_CUTOFF] = cap_port.low_pressure_cutoff
    row[L.P_ROD_HIGH_CUTOFF] = rod_port.high_pressure_cutoff
    row[L.P_ROD_LOW_CUTOFF] = rod_port.low_pressure_cutoff
    row[L.P_FRICTION_MODEL] = FRICTION_CODES[friction.model]
    row[L.P_FS] = friction.static_force
    row[L.P_FC] = friction.coulomb_force
    row[L.P_CV] = friction.viscous_coefficient
    row[L.P_VS] = friction.stribeck_velocity
    row[L.P_EXPONENT] = friction.stribeck_exponent
    row[L.P_KTANH] = friction.tanh_coefficient
    row[L.P_DAMPING] = friction.damping_coefficient
    row[L.P_SIGMA0] = friction.bristle_stiffness
    row[L.P_SIGMA1] = friction.bristle_damping
    row[L.P_THERMO_MODEL] = THERMO_CODES[thermo.model]
    row[L.P_POLYTROPIC_N] = thermo.polytropic_exponent
    row[L.P_HEAT_TRANSFER] = thermo.heat_transfer_coefficient
    row[L.P_WALL_TEMPERATURE] = thermo.wall_temperature
    return row


def initial_state(
    row: np.ndarray,
    position: float,
    cap_pressure: float,
    rod_pressure: float,
    temperature: float | None = None,
) -> np.ndarray:
    """Kernel state for an actuator at rest with given chamber pressures.

    Parameters
    ----------
    row : numpy.ndarray
        Packed parameters of the actuator.
    position : float
        Piston extension [m].
    cap_pressure, rod_pressure : float
        Absolute chamber pressures [Pa].
    temperature : float, optional
        Gas temperature [K]; the supply temperature by default.

    Returns
    -------
    numpy.ndarray
        State row of length N_STATES with masses from the ideal gas law (eq 4.1.7).
    """
    gas_temperature = row[L.P_TS] if temperature is None else temperature
    state = np.zeros(L.N_STATES)
    cap_volume = chamber_volume_cap(position, row[L.P_CAP_AREA], row[L.P_CAP_DEAD])
    rod_volume = chamber_volume_rod(
        position, row[L.P_STROKE], row[L.P_ROD_AREA], row[L.P_ROD_DEAD]
    )
    state[L.S_CAP_PRESSURE] = cap_pressure
    state[L.S_ROD_PRESSURE] = rod_pressure
    state[L.S_CAP_MASS] = cap_pressure * cap_volume / (row[L.P_R] * gas_temperature)
    state[L.S_ROD_MASS] = rod_pressure * rod_volume / (row[L.P_R] * gas_temperature)
    state[L.S_POSITION] = position
    return state


def supply_state(actuator: ActuatorParameters) -> np.ndarray:
    """Shared supply state for the kernels: ideal, or a tank at its initial pressure."""
    supply = np.zeros(L.N_SUPPLY)
    supply[L.SUPPLY_GAS_CONSTANT] = actuator.gas.gas_constant
    if actuator.supply.model == "tank":
        supply[L.SUPPLY_MODEL] = 1.0
        supply[L.SUPPLY_TANK_PRESSURE] = actuator.supply.tank_initial_pressure
        supply[L.SUPPLY_TANK_VOLUME] = actuator.supply.tank_volume
        supply[L.SUPPLY_TANK_TEMPERATURE] = actuator.supply.tank_temperature
    return supply


def pack_many(actuators: Sequence[ActuatorParameters]) -> np.ndarray:
    """Stack packed rows of several actuators into an (N, N_PARAMETERS) array."""
    return np.vstack([pack_parameters(actuator) for actuator in actuators])
