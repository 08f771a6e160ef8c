"""Object layer over the kernels: packing parameter objects and initial actuator states."""

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
)
from pneumaquad.core.physics.orifice import orifice_coefficients
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


def pack_parameters(actuator: ActuatorParameters) -> np.ndarray:
    """Pack one actuator's parameters into a kernel row (SI, see :mod:`pneumaquad.core.layout`).

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
    row = np.zeros(layout.N_PARAMETERS)
    c1, c2 = orifice_coefficients(gas.heat_capacity_ratio, gas.gas_constant)
    row[layout.P_K] = gas.heat_capacity_ratio
    row[layout.P_R] = gas.gas_constant
    row[layout.P_CP] = gas.specific_heat_cp
    row[layout.P_TS] = gas.supply_temperature
    row[layout.P_PATM] = gas.atmospheric_pressure
    row[layout.P_CRITICAL] = gas.critical_pressure_ratio
    row[layout.P_C1] = c1
    row[layout.P_C2] = c2
    row[layout.P_PS] = supply.supply_pressure
    row[layout.P_PE] = supply.exhaust_pressure
    row[layout.P_CAP_AREA] = cylinder.cap_area
    row[layout.P_ROD_AREA] = cylinder.rod_area
    row[layout.P_ROD_SECTION] = cylinder.rod_cross_section
    row[layout.P_STROKE] = cylinder.stroke
    row[layout.P_CAP_DEAD] = cylinder.cap_dead_length
    row[layout.P_ROD_DEAD] = cylinder.rod_dead_length
    row[layout.P_BORE] = cylinder.bore
    row[layout.P_PISTON_MASS] = cylinder.piston_mass
    row[layout.P_VALVE_MODEL] = VALVE_CODES[valve.model]
    row[layout.P_AREA_CURVE] = AREA_CURVE_CODES[valve.area_curve]
    row[layout.P_INPUT_PRESSURE] = INPUT_PRESSURE_CODES[valve.input_pressure]
    row[layout.P_FLOW_FORM] = FLOW_CODES[valve.flow_form]
    row[layout.P_OFFSET] = valve.offset_voltage
    row[layout.P_UMIN] = valve.min_voltage
    row[layout.P_UMAX] = valve.max_voltage
    row[layout.P_SPOOL_TAU] = valve.spool_time_constant
    row[layout.P_LAMINAR] = valve.laminar_pressure_ratio
    simple = valve.simple
    row[layout.P_SIMPLE_MAX_AREA] = simple.max_area
    row[layout.P_SIMPLE_LEAK_AREA] = simple.leak_area
    row[layout.P_SIMPLE_FULL_SCALE] = simple.full_scale_voltage
    row[layout.P_CD_CAP] = simple.cap_discharge_coefficient
    row[layout.P_CD_ROD] = simple.rod_discharge_coefficient
    row[layout.P_ISO_CONDUCTANCE] = simple.sonic_conductance
    row[layout.P_ISO_LEAK_CONDUCTANCE] = simple.leak_conductance
    row[layout.P_ISO_B] = simple.iso_critical_ratio
    cap_port, rod_port = chamber_ports(valve)
    row[layout.P_CAP_POLY_NEG : layout.P_CAP_POLY_NEG + 5] = cap_port.area_negative
    row[layout.P_CAP_POLY_POS : layout.P_CAP_POLY_POS + 5] = cap_port.area_positive
    row[layout.P_ROD_POLY_NEG : layout.P_ROD_POLY_NEG + 5] = rod_port.area_negative
    row[layout.P_ROD_POLY_POS : layout.P_ROD_POLY_POS + 5] = rod_port.area_positive
    row[layout.P_CAP_HIGH_CUTOFF] = cap_port.high_pressure_cutoff
    row[layout.P_CAP_LOW_CUTOFF] = cap_port.low_pressure_cutoff
    row[layout.P_ROD_HIGH_CUTOFF] = rod_port.high_pressure_cutoff
    row[layout.P_ROD_LOW_CUTOFF] = rod_port.low_pressure_cutoff
    row[layout.P_FRICTION_MODEL] = FRICTION_CODES[friction.model]
    row[layout.P_FS] = friction.static_force
    row[layout.P_FC] = friction.coulomb_force
    row[layout.P_CV] = friction.viscous_coefficient
    row[layout.P_VS] = friction.stribeck_velocity
    row[layout.P_EXPONENT] = friction.stribeck_exponent
    row[layout.P_KTANH] = friction.tanh_coefficient
    row[layout.P_DAMPING] = friction.damping_coefficient
    row[layout.P_SIGMA0] = friction.bristle_stiffness
    row[layout.P_SIGMA1] = friction.bristle_damping
    row[layout.P_THERMO_MODEL] = THERMO_CODES[thermo.model]
    row[layout.P_POLYTROPIC_N] = thermo.polytropic_exponent
    row[layout.P_HEAT_TRANSFER] = thermo.heat_transfer_coefficient
    row[layout.P_WALL_TEMPERATURE] = thermo.wall_temperature
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
    gas_temperature = row[layout.P_TS] if temperature is None else temperature
    state = np.zeros(layout.N_STATES)
    cap_volume = chamber_volume_cap(position, row[layout.P_CAP_AREA], row[layout.P_CAP_DEAD])
    rod_volume = chamber_volume_rod(
        position, row[layout.P_STROKE], row[layout.P_ROD_AREA], row[layout.P_ROD_DEAD]
    )
    state[layout.S_CAP_PRESSURE] = cap_pressure
    state[layout.S_ROD_PRESSURE] = rod_pressure
    state[layout.S_CAP_MASS] = cap_pressure * cap_volume / (row[layout.P_R] * gas_temperature)
    state[layout.S_ROD_MASS] = rod_pressure * rod_volume / (row[layout.P_R] * gas_temperature)
    state[layout.S_POSITION] = position
    return state


def supply_state(actuator: ActuatorParameters) -> np.ndarray:
    """Shared supply state for the kernels: ideal, or a tank at its initial pressure."""
    supply = np.zeros(layout.N_SUPPLY)
    supply[layout.SUPPLY_GAS_CONSTANT] = actuator.gas.gas_constant
    if actuator.supply.model == "tank":
        supply[layout.SUPPLY_MODEL] = 1.0
        supply[layout.SUPPLY_TANK_PRESSURE] = actuator.supply.tank_initial_pressure
        supply[layout.SUPPLY_TANK_VOLUME] = actuator.supply.tank_volume
        supply[layout.SUPPLY_TANK_TEMPERATURE] = actuator.supply.tank_temperature
    return supply
