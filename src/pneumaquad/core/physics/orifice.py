"""Compressible mass flow through a valve orifice (thesis eq 4.1.1–4.1.9, ISO 6358).

Sign convention: a flow from side *a* to side *b* is positive. The direction follows the
pressures, and the upstream temperature is taken from whichever side is upstream.
"""

import math

from pneumaquad.core.jit import compiled

#: ISO 8778 standard reference atmosphere (ANR) used by ISO 6358: density [kg/m^3].
ISO_REFERENCE_DENSITY = 1.185
#: ISO 8778 reference temperature [K].
ISO_REFERENCE_TEMPERATURE = 293.15


@compiled
def orifice_coefficients(heat_capacity_ratio: float, gas_constant: float) -> tuple[float, float]:
    """Flow constants C1 (unchoked) and C2 (choked) of eq 4.1.8 and 4.1.9.

    Parameters
    ----------
    heat_capacity_ratio : float
        k [-], 1.4 for air.
    gas_constant : float
        Specific gas constant R [J/(kg K)], 287 for air.

    Returns
    -------
    (C1, C2) : tuple of float
        C1 = sqrt(2k / (R (k-1))), C2 = sqrt(k / (R ((k+1)/2)^((k+1)/(k-1)))) [sqrt(kg K / J)].
    """
    k = heat_capacity_ratio
    c1 = math.sqrt(2.0 * k / (gas_constant * (k - 1.0)))
    c2 = math.sqrt(k / (gas_constant * ((k + 1.0) / 2.0) ** ((k + 1.0) / (k - 1.0))))
    return c1, c2


@compiled
def orifice_flux(
    upstream_pressure: float,
    downstream_pressure: float,
    upstream_temperature: float,
    heat_capacity_ratio: float,
    c1: float,
    c2: float,
    critical_ratio: float,
    laminar_ratio: float,
) -> float:
    """Mass flux per unit effective area, Psi of eq 4.1.5 (unchoked) and 4.1.6 (choked).

    Parameters
    ----------
    upstream_pressure, downstream_pressure : float
        Absolute pressures Pu >= Pd [Pa].
    upstream_temperature : float
        Tu [K].
    heat_capacity_ratio : float
        k [-].
    c1, c2 : float
        Constants of eq 4.1.8–4.1.9 (see :func:`orifice_coefficients`).
    critical_ratio : float
        Pd/Pu at and below which the flow is choked (0.528 for air, eq 4.1.4) [-].
    laminar_ratio : float
        Above this pressure ratio the flux falls linearly to zero at ratio 1 instead of
        following eq 4.1.5, whose slope is infinite there. This laminar regularisation
        bounds the stiffness of the chamber equations; 0.999 changes flows only where the
        pressure difference is below 0.1 % [-].

    Returns
    -------
    float
        Psi [kg/(s m^2)]; multiply by the effective area A(u)·cd (eq 4.1.1).
    """
    if upstream_pressure <= 0.0:
        return 0.0
    inverse_k = 1.0 / heat_capacity_ratio
    laminar_power, laminar_root = laminar_limit(laminar_ratio, inverse_k)
    return orifice_flux_of_ratio(
        downstream_pressure / upstream_pressure,
        upstream_pressure / math.sqrt(upstream_temperature),
        inverse_k,
        c1,
        c2,
        critical_ratio,
        laminar_ratio,
        laminar_power,
        laminar_root,
    )


@compiled
def laminar_limit(laminar_ratio: float, inverse_k: float) -> tuple[float, float]:
    """The two factors of eq 4.1.5 at the laminar limit ratio r_l.

    Parameters
    ----------
    laminar_ratio : float
        r_l [-] (see :func:`orifice_flux`).
    inverse_k : float
        1/k [-].

    Returns
    -------
    tuple of float
        (r_l^(1/k), sqrt(1 - r_l^((k-1)/k))) [-]: Psi at r_l is C1·Pu/sqrt(Tu) times both.
        Constants of the gas and the regularisation; the kernels compute them once per
        actuator and control step.
    """
    power = laminar_ratio**inverse_k
    return power, math.sqrt(1.0 - laminar_ratio / power)


@compiled
def orifice_flux_of_ratio(
    ratio: float,
    scale: float,
    inverse_k: float,
    c1: float,
    c2: float,
    critical_ratio: float,
    laminar_ratio: float,
    laminar_power: float,
    laminar_root: float,
) -> float:
    """:func:`orifice_flux` from its intermediate quantities, for callers that have them.

    The actuator kernels compute the pressure ratio once per port for the flow and its
    temperature (:func:`laminar_temperature_of_ratio`), and 1/k and the factors of the
    laminar limit once per control step.

    Parameters
    ----------
    ratio : float
        Pd/Pu, with Pu > 0 [-].
    scale : float
        Pu / sqrt(Tu) [Pa/sqrt(K)].
    inverse_k : float
        1/k [-].
    c1, c2, critical_ratio, laminar_ratio : float
        See :func:`orifice_flux`.
    laminar_power, laminar_root : float
        :func:`laminar_limit` of ``laminar_ratio`` and ``inverse_k`` [-].

    Returns
    -------
    float
        Psi [kg/(s m^2)].
    """
    if ratio <= critical_ratio:
        return c2 * scale
    if ratio >= 1.0:
        return 0.0
    if ratio > laminar_ratio:
        at_limit = c1 * scale * laminar_power * laminar_root
        return at_limit * (1.0 - ratio) / (1.0 - laminar_ratio)
    power = ratio**inverse_k
    # ratio**((k-1)/k) == ratio / ratio**(1/k): one power evaluation instead of two.
    return c1 * scale * power * math.sqrt(1.0 - ratio / power)


@compiled
def orifice_mass_flow(
    effective_area: float,
    pressure_a: float,
    pressure_b: float,
    temperature_a: float,
    temperature_b: float,
    heat_capacity_ratio: float,
    c1: float,
    c2: float,
    critical_ratio: float,
    laminar_ratio: float,
) -> float:
    """Signed mass flow from side a to side b through an orifice (eq 4.1.1–4.1.6).

    Parameters
    ----------
    effective_area : float
        Equivalent area cd·A(u) [m^2], >= 0.
    pressure_a, pressure_b : float
        Absolute pressures on both sides [Pa].
    temperature_a, temperature_b : float
        Gas temperatures on both sides [K]; the upstream one is used.
    heat_capacity_ratio, c1, c2, critical_ratio, laminar_ratio : float
        See :func:`orifice_flux`.

    Returns
    -------
    float
        Mass flow [kg/s], positive from a to b.
    """
    if pressure_a >= pressure_b:
        upstream_temperature = laminar_temperature(
            pressure_a, pressure_b, temperature_a, temperature_b, laminar_ratio
        )
        return effective_area * orifice_flux(
            pressure_a,
            pressure_b,
            upstream_temperature,
            heat_capacity_ratio,
            c1,
            c2,
            critical_ratio,
            laminar_ratio,
        )
    upstream_temperature = laminar_temperature(
        pressure_b, pressure_a, temperature_b, temperature_a, laminar_ratio
    )
    return -effective_area * orifice_flux(
        pressure_b,
        pressure_a,
        upstream_temperature,
        heat_capacity_ratio,
        c1,
        c2,
        critical_ratio,
        laminar_ratio,
    )


@compiled
def laminar_temperature(
    upstream_pressure: float,
    downstream_pressure: float,
    upstream_temperature: float,
    downstream_temperature: float,
    laminar_ratio: float,
) -> float:
    """Temperature to use for the flow: upstream, blended to the mean in the laminar band.

    In the laminar band the flux is linear in the pressure difference divided by
    sqrt(T). Moving T from the upstream value at the band's edge to the mean of both
    sides at equal pressures makes the flow smooth through zero, where a chamber at
    equilibrium sits; with the upstream temperature alone its slope would jump there
    (by sqrt(T_a/T_b)), which stalls implicit solvers. Outside the band it is the
    upstream temperature (eq 4.1.5–4.1.6, App. B.1.2 Port_2 l.52–62).

    Parameters
    ----------
    upstream_pressure, downstream_pressure : float
        Pu >= Pd [Pa].
    upstream_temperature, downstream_temperature : float
        [K].
    laminar_ratio : float
        Start of the laminar band [-].

    Returns
    -------
    float
        Temperature [K].
    """
    if upstream_pressure <= 0.0:
        return upstream_temperature
    return laminar_temperature_of_ratio(
        downstream_pressure / upstream_pressure,
        upstream_temperature,
        downstream_temperature,
        laminar_ratio,
    )


@compiled
def laminar_temperature_of_ratio(
    ratio: float,
    upstream_temperature: float,
    downstream_temperature: float,
    laminar_ratio: float,
) -> float:
    """:func:`laminar_temperature` from the pressure ratio Pd/Pu (Pu > 0) [-]."""
    if ratio <= laminar_ratio:
        return upstream_temperature
    weight = min((ratio - laminar_ratio) / (1.0 - laminar_ratio), 1.0)
    mean = 0.5 * (upstream_temperature + downstream_temperature)
    return upstream_temperature + (mean - upstream_temperature) * weight


@compiled
def iso6358_flux(
    upstream_pressure: float,
    downstream_pressure: float,
    upstream_temperature: float,
    critical_ratio: float,
    laminar_ratio: float,
) -> float:
    """ISO 6358 mass flow per unit sonic conductance.

    m_dot = C · rho0 · Pu · sqrt(T0/Tu) · phi, with phi = 1 when Pd/Pu <= b and
    phi = sqrt(1 - ((Pd/Pu - b)/(1 - b))^2) otherwise (ISO 6358-1).

    Parameters
    ----------
    upstream_pressure, downstream_pressure : float
        Absolute pressures Pu >= Pd [Pa].
    upstream_temperature : float
        Tu [K].
    critical_ratio : float
        b [-], 0 <= b < 1.
    laminar_ratio : float
        Linear fall to zero above this ratio, as in :func:`orifice_flux` [-].

    Returns
    -------
    float
        Mass flow per conductance [kg/s per m^3/(s Pa)].
    """
    if upstream_pressure <= 0.0:
        return 0.0
    return iso6358_flux_of_ratio(
        downstream_pressure / upstream_pressure,
        iso6358_scale(upstream_pressure, upstream_temperature),
        critical_ratio,
        laminar_ratio,
    )


@compiled
def iso6358_scale(upstream_pressure: float, upstream_temperature: float) -> float:
    """rho0 · Pu · sqrt(T0/Tu) of :func:`iso6358_flux` [kg/m^3 Pa]."""
    return (
        ISO_REFERENCE_DENSITY
        * upstream_pressure
        * math.sqrt(ISO_REFERENCE_TEMPERATURE / upstream_temperature)
    )


@compiled
def iso6358_flux_of_ratio(
    ratio: float, scale: float, critical_ratio: float, laminar_ratio: float
) -> float:
    """:func:`iso6358_flux` from the pressure ratio Pd/Pu (Pu > 0) and
    :func:`iso6358_scale`."""
    if ratio <= critical_ratio:
        return scale
    if ratio >= 1.0:
        return 0.0
    if ratio > laminar_ratio:
        shape = (laminar_ratio - critical_ratio) / (1.0 - critical_ratio)
        at_limit = scale * math.sqrt(1.0 - shape * shape)
        return at_limit * (1.0 - ratio) / (1.0 - laminar_ratio)
    shape = (ratio - critical_ratio) / (1.0 - critical_ratio)
    return scale * math.sqrt(1.0 - shape * shape)


@compiled
def iso6358_mass_flow(
    sonic_conductance: float,
    pressure_a: float,
    pressure_b: float,
    temperature_a: float,
    temperature_b: float,
    critical_ratio: float,
    laminar_ratio: float,
) -> float:
    """Signed ISO 6358 mass flow from side a to side b.

    Parameters
    ----------
    sonic_conductance : float
        C [m^3/(s Pa)], >= 0 (datasheets give dm^3/(s bar) = 1e-8 m^3/(s Pa)).
    pressure_a, pressure_b : float
        Absolute pressures [Pa].
    temperature_a, temperature_b : float
        Temperatures [K]; the upstream one is used.
    critical_ratio : float
        b [-].
    laminar_ratio : float
        See :func:`iso6358_flux`.

    Returns
    -------
    float
        Mass flow [kg/s], positive from a to b.
    """
    if pressure_a >= pressure_b:
        upstream_temperature = laminar_temperature(
            pressure_a, pressure_b, temperature_a, temperature_b, laminar_ratio
        )
        return sonic_conductance * iso6358_flux(
            pressure_a, pressure_b, upstream_temperature, critical_ratio, laminar_ratio
        )
    upstream_temperature = laminar_temperature(
        pressure_b, pressure_a, temperature_b, temperature_a, laminar_ratio
    )
    return -sonic_conductance * iso6358_flux(
        pressure_b, pressure_a, upstream_temperature, critical_ratio, laminar_ratio
    )


@compiled
def area_to_sonic_conductance(effective_area: float, c2: float) -> float:
    """Sonic conductance with the same choked flow as an orifice of a given area.

    Equating A·C2·Pu/sqrt(Tu) (eq 4.1.6) with C·rho0·Pu·sqrt(T0/Tu) gives
    C = A·C2 / (rho0·sqrt(T0)).

    Parameters
    ----------
    effective_area : float
        cd·A [m^2].
    c2 : float
        Choked-flow constant of eq 4.1.9.

    Returns
    -------
    float
        C [m^3/(s Pa)].
    """
    return effective_area * c2 / (ISO_REFERENCE_DENSITY * math.sqrt(ISO_REFERENCE_TEMPERATURE))
