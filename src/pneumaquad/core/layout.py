"""Named records of the compiled kernels: actuator parameters, state, outputs, supply.

Each actuator is one record of a NumPy structured dtype; N actuators are an array of
them. The compiled code reads fields by name (``p.cap_area``, ``state[i].cap_pressure``),
which numba lowers to fixed offsets, as fast as indexing a float row. Enumerations are
integer fields compared with the named constants below; the valve's polynomial
coefficients are sub-arrays of five values, highest power first. Units are SI.

Packing from the validated parameter objects is :mod:`pneumaquad.core.actuator` (and
:mod:`pneumaquad.rig.model` for the rig fields). :func:`float_view` is the one conversion
to plain floats, for code that needs a float vector (the adaptive solver's state).
"""

import numpy as np
from numpy.lib.recfunctions import structured_to_unstructured

__all__ = [
    "ACTUATOR_OUTPUT_DTYPE",
    "ACTUATOR_PARAMETERS_DTYPE",
    "ACTUATOR_STATE_DTYPE",
    "AREA_LINEAR",
    "AREA_POLYNOMIAL",
    "FLOW_ISO6358",
    "FLOW_ORIFICE",
    "INPUT_SWITCHED",
    "INPUT_TANH",
    "POLYNOMIAL_COEFFICIENTS",
    "RIG_PARAMETER_FIELDS",
    "STEP_WORK_DTYPE",
    "SUPPLY_DTYPE",
    "SUPPLY_IDEAL",
    "SUPPLY_TANK",
    "VALVE_SIMPLE",
    "VALVE_UNDERLAPPED",
    "float_view",
    "state_field_index",
]

#: Coefficients of each equivalent-area polynomial (4th order).
POLYNOMIAL_COEFFICIENTS = 5

# --- enumerations (integer fields) -----------------------------------------------------
VALVE_SIMPLE = 0  # valve_model: linear slot area, fixed supply/exhaust pressures
VALVE_UNDERLAPPED = 1  # valve_model: the thesis's fitted underlapped valve
FLOW_ORIFICE = 0  # flow_form: compressible orifice flow (eq 4.1.8, 4.1.9)
FLOW_ISO6358 = 1  # flow_form: ISO 6358 sonic conductance C and critical ratio b
AREA_POLYNOMIAL = 0  # area_curve: fitted polynomials (thesis 4.2.3)
AREA_LINEAR = 1  # area_curve: the simple valve's linear slot area
INPUT_TANH = 0  # input_pressure_curve: tanh input pressures (eq 4.2.7)
INPUT_SWITCHED = 1  # input_pressure_curve: plain supply/exhaust switching
SUPPLY_IDEAL = 0  # supply model: regulated, unlimited
SUPPLY_TANK = 1  # supply model: finite isothermal tank behind the regulator

#: Parameters of one actuator (valve + cylinder + friction + chambers), plus the fields of
#: the single-DoF rig that :func:`pneumaquad.core.kernel.step_rigs` reads.
ACTUATOR_PARAMETERS_DTYPE = np.dtype([
    # gas
    ("heat_capacity_ratio", "f8"),  # k [-]
    ("gas_constant", "f8"),  # R [J/(kg K)]
    ("specific_heat_cp", "f8"),  # cp [J/(kg K)]
    ("supply_temperature", "f8"),  # Ts [K]
    ("atmospheric_pressure", "f8"),  # [Pa]
    ("critical_pressure_ratio", "f8"),  # [-]
    ("unchoked_flow_constant", "f8"),  # C1 of eq 4.1.8 [sqrt(kg K/J)]
    ("choked_flow_constant", "f8"),  # C2 of eq 4.1.9 [sqrt(kg K/J)]
    # derived from the gas, the thermodynamic model and the laminar ratio when packed
    # (pneumatics.flow_constants reads the first three, pneumatics.port_flow the others;
    # none changes after packing)
    ("inverse_heat_capacity_ratio", "f8"),  # 1/k of eq 4.1.5 [-]
    ("flow_coefficient", "f8"),  # k, or n (polytropic), of eq 4.1.10 [-]
    ("compression_exponent", "f8"),  # k*R/cp + 1, or n, of eq 4.1.10 [-]
    ("laminar_power", "f8"),  # r_l^(1/k) (physics.orifice.laminar_limit) [-]
    ("laminar_root", "f8"),  # sqrt(1 - r_l^((k-1)/k)) [-]
    ("supply_temperature_root", "f8"),  # sqrt(Ts) [sqrt(K)]
    # supply
    ("supply_pressure", "f8"),  # regulated supply pressure [Pa]
    ("exhaust_pressure", "f8"),  # [Pa]
    # cylinder
    ("cap_area", "f8"),  # piston area on the cap side [m^2]
    ("rod_area", "f8"),  # annulus area on the rod side [m^2]
    ("rod_cross_section", "f8"),  # rod section under atmospheric pressure [m^2]
    ("stroke", "f8"),  # [m]
    ("cap_dead_length", "f8"),  # cap dead volume / cap area [m]
    ("rod_dead_length", "f8"),  # rod dead volume / rod area [m]
    ("bore", "f8"),  # [m]
    ("piston_mass", "f8"),  # piston and rod [kg]
    # valve
    ("valve_model", "i8"),  # VALVE_SIMPLE / VALVE_UNDERLAPPED
    ("flow_form", "i8"),  # FLOW_ORIFICE / FLOW_ISO6358
    ("area_curve", "i8"),  # AREA_POLYNOMIAL / AREA_LINEAR (underlapped valve)
    ("input_pressure_curve", "i8"),  # INPUT_TANH / INPUT_SWITCHED (underlapped valve)
    ("offset_voltage", "f8"),  # valve centre [V]
    ("min_voltage", "f8"),  # [V]
    ("max_voltage", "f8"),  # [V]
    ("spool_time_constant", "f8"),  # first-order spool lag [s], 0 = none
    ("laminar_pressure_ratio", "f8"),  # [-]
    ("valve_area_scale", "f8"),  # factor on every orifice area of the valve [-]
    # simple valve (and the linear area curve of the underlapped one)
    ("simple_max_area", "f8"),  # [m^2]
    ("simple_leak_area", "f8"),  # [m^2]
    ("simple_full_scale_voltage", "f8"),  # [V]
    ("cap_discharge_coefficient", "f8"),  # [-]
    ("rod_discharge_coefficient", "f8"),  # [-]
    ("sonic_conductance", "f8"),  # ISO 6358 C [m^3/(s Pa)]
    ("leak_conductance", "f8"),  # [m^3/(s Pa)]
    ("iso_critical_ratio", "f8"),  # ISO 6358 b [-]
    # underlapped valve: the ports feeding the cap and rod chambers
    ("cap_polynomial_negative", "f8", POLYNOMIAL_COEFFICIENTS),  # [m^2/V^n]
    ("cap_polynomial_positive", "f8", POLYNOMIAL_COEFFICIENTS),  # [m^2/V^n]
    ("rod_polynomial_negative", "f8", POLYNOMIAL_COEFFICIENTS),  # [m^2/V^n]
    ("rod_polynomial_positive", "f8", POLYNOMIAL_COEFFICIENTS),  # [m^2/V^n]
    ("cap_high_pressure_cutoff", "f8"),  # eq 4.2.7 [V]
    ("cap_low_pressure_cutoff", "f8"),  # [V]
    ("rod_high_pressure_cutoff", "f8"),  # [V]
    ("rod_low_pressure_cutoff", "f8"),  # [V]
    # friction (FRICTION_* of pneumaquad.core.physics.friction)
    ("friction_model", "i8"),
    ("static_force", "f8"),  # Fs [N]
    ("coulomb_force", "f8"),  # Fc [N]
    ("viscous_coefficient", "f8"),  # Cv [N s/m]
    ("stribeck_velocity", "f8"),  # vS [m/s]
    ("stribeck_exponent", "f8"),  # [-]
    ("stribeck_flat_velocity", "f8"),  # below it g(v) is exactly Fs [m/s] (derived)
    ("tanh_coefficient", "f8"),  # [s/m]
    ("damping_coefficient", "f8"),  # viscous model [N s/m]
    ("bristle_stiffness", "f8"),  # LuGre sigma0 [N/m]
    ("bristle_damping", "f8"),  # LuGre sigma1 [N s/m]
    # chamber thermodynamics (THERMO_* of pneumaquad.core.physics.chamber)
    ("thermo_model", "i8"),
    ("polytropic_exponent", "f8"),  # [-]
    ("heat_transfer_coefficient", "f8"),  # [W/(m^2 K)]
    ("wall_temperature", "f8"),  # [K]
    # single-DoF rig (pneumaquad.rig.model; the externally driven kernel ignores these)
    ("moving_mass", "f8"),  # load + piston [kg]
    ("gravity_force", "f8"),  # weight along +x [N]
    ("end_stop_stiffness", "f8"),  # [N/m]
    ("end_stop_damping", "f8"),  # [N s/m]
    ("spacer", "i8"),  # 1: piston fixed at full extension by a spacer, else 0
])

#: Fields of :data:`ACTUATOR_PARAMETERS_DTYPE` that only the rig kernel reads; packing an
#: actuator alone sets them to zero.
RIG_PARAMETER_FIELDS = (
    "moving_mass", "gravity_force", "end_stop_stiffness", "end_stop_damping", "spacer",
)

#: State of one actuator, advanced in place by the kernels (all float64: see
#: :func:`float_view`).
ACTUATOR_STATE_DTYPE = np.dtype([
    ("cap_pressure", "f8"),  # absolute [Pa]
    ("rod_pressure", "f8"),  # absolute [Pa]
    ("cap_mass", "f8"),  # air in the cap chamber [kg]
    ("rod_mass", "f8"),  # air in the rod chamber [kg]
    ("spool_voltage", "f8"),  # effective centered voltage after the spool lag [V]
    ("bristle_deflection", "f8"),  # LuGre bristle deflection [m]
    ("air_consumed", "f8"),  # mass drawn from the supply since the start [kg]
    ("position", "f8"),  # piston extension [m] (an input of the externally driven kernel)
    ("velocity", "f8"),  # piston velocity [m/s]
])

#: What one control step of one actuator produced.
ACTUATOR_OUTPUT_DTYPE = np.dtype([
    ("cap_mass_flow", "f8"),  # mean net mass flow into the cap chamber over the step [kg/s]
    ("rod_mass_flow", "f8"),  # mean net mass flow into the rod chamber over the step [kg/s]
    ("pneumatic_force", "f8"),  # eq 4.1.11 without friction, end of step [N]
    ("friction_force", "f8"),  # [N]
    ("end_stop_force", "f8"),  # [N]
    ("cap_temperature", "f8"),  # end of step [K]
    ("rod_temperature", "f8"),  # end of step [K]
    ("supply_mass_flow", "f8"),  # mean mass flow drawn from the supply [kg/s]
])

#: The supply all actuators of a kernel call share (an array of one record).
SUPPLY_DTYPE = np.dtype([
    ("model", "i8"),  # SUPPLY_IDEAL / SUPPLY_TANK
    ("tank_pressure", "f8"),  # [Pa] (tank)
    ("tank_volume", "f8"),  # [m^3] (tank)
    ("tank_temperature", "f8"),  # [K] (tank)
    ("drawn_mass", "f8"),  # total mass drawn from the supply [kg]
    ("gas_constant", "f8"),  # R of the stored gas [J/(kg K)]
])

#: What one actuator's control step keeps between its substeps: the kernels advance all
#: actuators substep by substep (the next actuator's arithmetic does not wait on this
#: one's, so the processor overlaps them), and hold here what each set up at the step's
#: start. Internal to :mod:`pneumaquad.core.kernel`.
STEP_WORK_DTYPE = np.dtype([
    ("target_voltage", "f8"),  # centered valve command of the step [V]
    ("supply_pressure", "f8"),  # pressure the regulator delivers over the step [Pa]
    ("cap_source_pressure", "f8"),  # what the cap port sees [Pa] (valve_connections)
    ("cap_conductance", "f8"),  # cd*A [m^2] or ISO 6358 C [m^3/(s Pa)]
    ("rod_source_pressure", "f8"),  # [Pa]
    ("rod_conductance", "f8"),  # as cap_conductance
    ("drawn_mass", "f8"),  # drawn from the supply over the step so far [kg]
])


def float_view(records: np.ndarray) -> np.ndarray:
    """The same memory as plain floats: ``(..., fields)`` float64 of an all-float64
    record array (:data:`ACTUATOR_STATE_DTYPE`, :data:`ACTUATOR_OUTPUT_DTYPE`), columns in
    field order. For a solver or a stack of snapshots that needs a float vector; the
    kernels themselves read fields by name."""
    fields = len(records.dtype.names)
    if records.dtype.itemsize != 8 * fields or any(
        records.dtype[name] != np.float64 for name in records.dtype.names
    ):
        raise TypeError(f"float_view needs float64 fields only, got {records.dtype}")
    return structured_to_unstructured(records, copy=False)  # a view, strided or not


def state_field_index(name: str) -> int:
    """Column of state field ``name`` in :func:`float_view` of state records."""
    return ACTUATOR_STATE_DTYPE.names.index(name)
