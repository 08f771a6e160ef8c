"""Cylinder chambers: volume, ideal-gas temperature and the energy balance (thesis 4.1.2).

Piston position x [m] is the extension from full retraction: the cap chamber grows with x,
the rod chamber shrinks. Dead volumes are expressed as lengths of the chamber's own area.
"""

from pneumaquad.core.jit import compiled

#: Thermodynamics model codes.
THERMO_ADIABATIC = 0
THERMO_POLYTROPIC = 1
THERMO_HEAT_TRANSFER = 2


@compiled
def chamber_volume_cap(position: float, cap_area: float, cap_dead_length: float) -> float:
    """Cap-side volume V = A_cap·(x + x_dead) [m^3] (x_abs of eq 4.1.7).

    Parameters
    ----------
    position : float
        Piston extension x [m].
    cap_area : float
        Cap-side piston area [m^2].
    cap_dead_length : float
        Dead volume as a length of cap area [m] (0.012 m, App. B.1.1 l.49).
    """
    return cap_area * max(position + cap_dead_length, 1e-6)


@compiled
def chamber_volume_rod(
    position: float, stroke: float, rod_area: float, rod_dead_length: float
) -> float:
    """Rod-side volume V = A_rod·(stroke - x + x_dead) [m^3].

    Parameters
    ----------
    position : float
        Piston extension x [m].
    stroke : float
        Cylinder stroke [m].
    rod_area : float
        Annulus area A_cap - pi d_rod^2/4 [m^2].
    rod_dead_length : float
        Dead volume as a length of annulus [m] (0.018 m, App. B.1.1 l.48).
    """
    return rod_area * max(stroke - position + rod_dead_length, 1e-6)


@compiled
def chamber_temperature(pressure: float, volume: float, mass: float, gas_constant: float) -> float:
    """Ideal-gas temperature T = P·V / (m·R) (eq 4.1.7).

    Parameters
    ----------
    pressure : float
        Absolute pressure [Pa].
    volume : float
        Chamber volume [m^3].
    mass : float
        Air mass in the chamber [kg].
    gas_constant : float
        R [J/(kg K)].

    Returns
    -------
    float
        Temperature [K].
    """
    return pressure * volume / (mass * gas_constant)


@compiled
def chamber_pressure_rate(
    pressure: float,
    volume: float,
    volume_rate: float,
    mass_flow_in: float,
    flow_temperature: float,
    chamber_temp: float,
    wall_area: float,
    heat_capacity_ratio: float,
    gas_constant: float,
    specific_heat_cp: float,
    thermo_model: int,
    polytropic_exponent: float,
    heat_transfer_coefficient: float,
    wall_temperature: float,
) -> float:
    """Rate of change of chamber pressure, the energy balance of eq 4.1.10.

    Adiabatic (thesis form): dP/dt = k·R·T_f·m_dot / V - (k·R/cp + 1)·P·(dV/dt) / V.
    The thesis writes dV/dt / V as x_dot / x_abs. With cp = 1012 J/(kg K) the compression
    exponent k·R/cp + 1 is 1.397, so a closed chamber follows P·V^1.397 = const.

    Polytropic: k and the compression exponent are both replaced by n.
    Heat transfer: the adiabatic form plus (k - 1)·h·A_w·(T_wall - T) / V.

    Parameters
    ----------
    pressure : float
        Chamber pressure [Pa].
    volume, volume_rate : float
        Chamber volume [m^3] and its rate [m^3/s].
    mass_flow_in : float
        Net mass flow into the chamber [kg/s].
    flow_temperature : float
        Temperature of the flowing air: supply temperature when filling, chamber
        temperature when emptying [K].
    chamber_temp : float
        Chamber temperature [K] (heat transfer only).
    wall_area : float
        Wetted wall area [m^2] (heat transfer only).
    heat_capacity_ratio, gas_constant, specific_heat_cp : float
        k [-], R [J/(kg K)], cp [J/(kg K)].
    thermo_model : int
        THERMO_ADIABATIC, THERMO_POLYTROPIC or THERMO_HEAT_TRANSFER.
    polytropic_exponent : float
        n [-] (polytropic only).
    heat_transfer_coefficient : float
        h [W/(m^2 K)] (heat transfer only).
    wall_temperature : float
        T_wall [K] (heat transfer only).

    Returns
    -------
    float
        dP/dt [Pa/s].
    """
    flow_coefficient, compression = energy_exponents(
        thermo_model, heat_capacity_ratio, gas_constant, specific_heat_cp, polytropic_exponent
    )
    return chamber_pressure_rate_of_exponents(
        pressure,
        volume,
        volume_rate,
        mass_flow_in,
        flow_temperature,
        chamber_temp,
        wall_area,
        flow_coefficient,
        compression,
        heat_capacity_ratio,
        gas_constant,
        thermo_model,
        heat_transfer_coefficient,
        wall_temperature,
    )


@compiled
def energy_exponents(
    thermo_model: int,
    heat_capacity_ratio: float,
    gas_constant: float,
    specific_heat_cp: float,
    polytropic_exponent: float,
) -> tuple[float, float]:
    """Coefficients of the inflow and of the compression term in eq 4.1.10.

    Returns
    -------
    (float, float)
        (k, k·R/cp + 1), or (n, n) for the polytropic model (see
        :func:`chamber_pressure_rate`).
    """
    if thermo_model == THERMO_POLYTROPIC:
        return polytropic_exponent, polytropic_exponent
    return heat_capacity_ratio, heat_capacity_ratio * gas_constant / specific_heat_cp + 1.0


@compiled
def chamber_pressure_rate_of_exponents(
    pressure: float,
    volume: float,
    volume_rate: float,
    mass_flow_in: float,
    flow_temperature: float,
    chamber_temp: float,
    wall_area: float,
    flow_coefficient: float,
    compression: float,
    heat_capacity_ratio: float,
    gas_constant: float,
    thermo_model: int,
    heat_transfer_coefficient: float,
    wall_temperature: float,
) -> float:
    """:func:`chamber_pressure_rate` with the coefficients of :func:`energy_exponents`
    given, for callers that compute them once per step rather than per evaluation."""
    rate = (
        flow_coefficient * gas_constant * flow_temperature * mass_flow_in
        - compression * pressure * volume_rate
    ) / volume
    if thermo_model == THERMO_HEAT_TRANSFER:
        heat_flow = heat_transfer_coefficient * wall_area * (wall_temperature - chamber_temp)
        rate += (heat_capacity_ratio - 1.0) * heat_flow / volume
    return rate
