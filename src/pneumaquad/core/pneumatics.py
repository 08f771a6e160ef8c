"""Per-actuator pneumatic building blocks of the compiled kernels.

What one actuator's chambers do over a substep: which pressure each port sees and
through what conductance (valve map), the port mass flows, the chamber pressure and mass
rates (eq 4.1.7, 4.1.10), a Heun substep of those states, the spool lag, the LuGre
bristle update, the supply draw and the end-of-step outputs. :mod:`pneumaquad.core.kernel`
loops these over actuators and substeps.

Every function takes one actuator's records (:mod:`pneumaquad.core.layout`): ``p`` its
parameters, ``s`` its state (updated in place), ``out`` its outputs, ``supply`` the shared
supply record.
"""

import math
from typing import NamedTuple

from pneumaquad.core.jit import compiled
from pneumaquad.core.layout import (
    AREA_LINEAR,
    FLOW_ISO6358,
    INPUT_SWITCHED,
    SUPPLY_TANK,
    VALVE_SIMPLE,
)
from pneumaquad.core.physics.chamber import (
    THERMO_HEAT_TRANSFER,
    chamber_pressure_rate_of_exponents,
    chamber_temperature,
    chamber_volume_cap,
    chamber_volume_rod,
    energy_exponents,
)
from pneumaquad.core.physics.force import piston_force
from pneumaquad.core.physics.friction import (
    FRICTION_LUGRE,
    FRICTION_STRIBECK_TANH,
    friction_damping,
    friction_force,
    lugre_bristle_update,
    stribeck_curve,
    stribeck_tanh_force_and_slope_of_curve,
)
from pneumaquad.core.physics.orifice import (
    area_to_sonic_conductance,
    iso6358_flux_of_ratio,
    iso6358_scale,
    laminar_temperature_of_ratio,
    orifice_flux_of_ratio,
)
from pneumaquad.core.physics.valve import (
    centered_voltage,
    input_pressure,
    polynomial_area,
    simple_valve_area,
)


@compiled
def supply_pressure_now(p, supply) -> float:
    """Pressure delivered by the regulator: the set point, or less if the tank is lower."""
    if supply.model == SUPPLY_TANK:
        return min(p.supply_pressure, supply.tank_pressure)
    return p.supply_pressure


@compiled
def valve_connections(p, centered: float, supply_pressure: float):
    """What each chamber is connected to at a centered valve voltage.

    Returns (cap source pressure [Pa], cap conductance, rod source pressure [Pa], rod
    conductance). Conductance is an effective area cd·A [m^2] for the orifice form and a
    sonic conductance [m^3/(s Pa)] for the ISO 6358 form, either times the valve's
    ``area_scale`` (1 as fitted; a sizing factor). Simple valve: positive voltage
    connects the cap to supply and the rod to exhaust (thesis Fig. 18). Underlapped valve:
    each port sees the tanh input pressure of eq 4.2.7 through its polynomial area; either
    part can be swapped for the simple valve's (``input_pressure_curve`` switched
    supply/exhaust, ``area_curve`` linear area), the separate rows of thesis Table 3.
    """
    exhaust = p.exhaust_pressure
    iso = p.flow_form == FLOW_ISO6358
    scale = p.valve_area_scale
    if p.valve_model == VALVE_SIMPLE:
        if iso:
            span = abs(centered) / p.simple_full_scale_voltage
            cap_conductance = (p.sonic_conductance * span + p.leak_conductance) * scale
            rod_conductance = cap_conductance
        else:
            area = simple_valve_area(
                centered, p.simple_max_area, p.simple_leak_area, p.simple_full_scale_voltage
            )
            cap_conductance = p.cap_discharge_coefficient * area * scale
            rod_conductance = p.rod_discharge_coefficient * area * scale
        if centered >= 0.0:
            return supply_pressure, cap_conductance, exhaust, rod_conductance
        return exhaust, cap_conductance, supply_pressure, rod_conductance
    if p.input_pressure_curve == INPUT_SWITCHED:
        # the simple valve's plain supply/exhaust pressures (thesis Table 3 ablation)
        if centered >= 0.0:
            cap_source, rod_source = supply_pressure, exhaust
        else:
            cap_source, rod_source = exhaust, supply_pressure
    else:
        cap_source = input_pressure(
            centered, supply_pressure, exhaust, p.cap_high_pressure_cutoff,
            p.cap_low_pressure_cutoff,
        )
        rod_source = input_pressure(
            centered, supply_pressure, exhaust, p.rod_high_pressure_cutoff,
            p.rod_low_pressure_cutoff,
        )
    if p.area_curve == AREA_LINEAR:
        # the simple valve's linear slot area (thesis Table 3 ablation)
        area = simple_valve_area(
            centered, p.simple_max_area, p.simple_leak_area, p.simple_full_scale_voltage
        )
        cap_area = p.cap_discharge_coefficient * area * scale
        rod_area = p.rod_discharge_coefficient * area * scale
    else:
        cap_area = polynomial_area(
            centered, p.cap_polynomial_negative, p.cap_polynomial_positive
        ) * scale
        rod_area = polynomial_area(
            centered, p.rod_polynomial_negative, p.rod_polynomial_positive
        ) * scale
    if iso:
        return (
            cap_source,
            area_to_sonic_conductance(cap_area, p.choked_flow_constant),
            rod_source,
            area_to_sonic_conductance(rod_area, p.choked_flow_constant),
        )
    return cap_source, cap_area, rod_source, rod_area


class FlowConstants(NamedTuple):
    """An actuator's constants of the port flows and the energy balance (all [-]), handed
    down the rate evaluations. (The laminar limit's factors and √Ts, packed with the
    parameters too, are read from the record where they are used: three more fields
    handed down every call made the lone rig's step 4 % slower.)"""

    inverse_heat_capacity_ratio: float  # 1/k of eq 4.1.5
    flow_coefficient: float  # k, or n (polytropic), of eq 4.1.10
    compression_exponent: float  # k·R/cp + 1, or n, of eq 4.1.10


@compiled
def flow_constants(p):
    """The actuator's :class:`FlowConstants` (fields of its packed parameters, derived
    once by :func:`derived_flow_constants`)."""
    return FlowConstants(p.inverse_heat_capacity_ratio, p.flow_coefficient,
                         p.compression_exponent)


@compiled
def derived_flow_constants(
    heat_capacity_ratio, gas_constant, specific_heat_cp, thermo_model, polytropic_exponent,
):
    """The :class:`FlowConstants` of a gas and a thermodynamic model: of eq 4.1.5 and
    4.1.10 (see :func:`pneumaquad.core.physics.chamber.energy_exponents`). Computed once
    when the parameters are packed (``pneumaquad.core.actuator.pack_parameters``, with
    the laminar limit of :func:`pneumaquad.core.physics.orifice.laminar_limit` and √Ts),
    so that no rate evaluation divides or raises to a power for them again.
    """
    flow_coefficient, compression = energy_exponents(
        thermo_model, heat_capacity_ratio, gas_constant, specific_heat_cp,
        polytropic_exponent,
    )
    return FlowConstants(1.0 / heat_capacity_ratio, flow_coefficient, compression)


@compiled
def port_flow(p, constants, conductance, source_pressure, pressure, temperature):
    """Mass flow into a chamber from its valve port [kg/s] and the temperature of the air
    crossing the port [K].

    The same law as :func:`pneumaquad.core.physics.orifice.orifice_mass_flow` (or the ISO
    6358 form). The crossing air is at supply temperature when filling and at the
    chamber's ``temperature`` when emptying, blended to their mean near equal pressures
    (:func:`pneumaquad.core.physics.orifice.laminar_temperature`), so that flow and energy
    balance stay smooth through zero flow; the energy balance needs that temperature too.
    The pressure ratio is computed once for both. ``constants`` is :func:`flow_constants`.
    """
    if source_pressure >= pressure:
        upstream, downstream, sign = source_pressure, pressure, 1.0
        upstream_temperature, downstream_temperature = p.supply_temperature, temperature
    else:
        upstream, downstream, sign = pressure, source_pressure, -1.0
        upstream_temperature, downstream_temperature = temperature, p.supply_temperature
    if upstream <= 0.0:
        return sign * conductance * 0.0, upstream_temperature
    ratio = downstream / upstream
    crossing = laminar_temperature_of_ratio(
        ratio, upstream_temperature, downstream_temperature, p.laminar_pressure_ratio
    )
    if p.flow_form == FLOW_ISO6358:
        flux = iso6358_flux_of_ratio(
            ratio,
            iso6358_scale(upstream, crossing),
            p.iso_critical_ratio,
            p.laminar_pressure_ratio,
        )
    else:
        if crossing == p.supply_temperature:  # filling: the root known beforehand
            root = p.supply_temperature_root
        else:
            root = math.sqrt(crossing)
        flux = orifice_flux_of_ratio(
            ratio,
            upstream / root,
            constants.inverse_heat_capacity_ratio,
            p.unchoked_flow_constant,
            p.choked_flow_constant,
            p.critical_pressure_ratio,
            p.laminar_pressure_ratio,
            p.laminar_power,
            p.laminar_root,
        )
    return sign * conductance * flux, crossing


@compiled
def chamber_rate(
    p, constants, pressure, temperature, volume, volume_rate, flow_in, flow_temp, wall_area
):
    """dP/dt of one chamber (eq 4.1.10) given its temperature and net inflow."""
    return chamber_pressure_rate_of_exponents(
        pressure,
        volume,
        volume_rate,
        flow_in,
        flow_temp,
        temperature,
        wall_area,
        constants.flow_coefficient,
        constants.compression_exponent,
        p.heat_capacity_ratio,
        p.gas_constant,
        p.thermo_model,
        p.heat_transfer_coefficient,
        p.wall_temperature,
    )


@compiled
def pneumatic_rates(
    p,
    constants,
    cap_pressure,
    rod_pressure,
    cap_mass,
    rod_mass,
    position,
    velocity,
    cap_source,
    cap_conductance,
    rod_source,
    rod_conductance,
):
    """Rates of the four chamber states and the supply draw for one actuator.

    ``constants`` is :func:`flow_constants` of ``p``. Returns (dP_cap/dt [Pa/s],
    dP_rod/dt [Pa/s], m_dot_cap [kg/s], m_dot_rod [kg/s], supply draw [kg/s]).
    """
    cap_volume = chamber_volume_cap(position, p.cap_area, p.cap_dead_length)
    rod_volume = chamber_volume_rod(position, p.stroke, p.rod_area, p.rod_dead_length)
    cap_temperature = chamber_temperature(cap_pressure, cap_volume, cap_mass, p.gas_constant)
    rod_temperature = chamber_temperature(rod_pressure, rod_volume, rod_mass, p.gas_constant)
    cap_flow, cap_crossing = port_flow(
        p, constants, cap_conductance, cap_source, cap_pressure, cap_temperature
    )
    rod_flow, rod_crossing = port_flow(
        p, constants, rod_conductance, rod_source, rod_pressure, rod_temperature
    )
    cap_wall = 0.0
    rod_wall = 0.0
    if p.thermo_model == THERMO_HEAT_TRANSFER:
        end_faces = 0.5 * math.pi * p.bore * p.bore
        cap_wall = end_faces + math.pi * p.bore * cap_volume / p.cap_area
        rod_wall = end_faces + math.pi * p.bore * rod_volume / p.rod_area
    cap_rate = chamber_rate(
        p,
        constants,
        cap_pressure,
        cap_temperature,
        cap_volume,
        p.cap_area * velocity,
        cap_flow,
        cap_crossing,
        cap_wall,
    )
    rod_rate = chamber_rate(
        p,
        constants,
        rod_pressure,
        rod_temperature,
        rod_volume,
        -p.rod_area * velocity,
        rod_flow,
        rod_crossing,
        rod_wall,
    )
    draw = 0.0
    exhaust = p.exhaust_pressure
    if cap_flow > 0.0 and cap_source > exhaust:
        draw += cap_flow
    if rod_flow > 0.0 and rod_source > exhaust:
        draw += rod_flow
    return cap_rate, rod_rate, cap_flow, rod_flow, draw


@compiled
def spool_update(p, spool: float, target: float, time_step: float) -> float:
    """First-order spool lag (valve bandwidth) advanced exactly over a step (tau > 0)."""
    tau = p.spool_time_constant
    return target + (spool - target) * math.exp(-time_step / tau)


@compiled
def heun_pneumatics(p, constants, s, position, velocity, time_step, connections, out):
    """One Heun substep of the chamber states with the piston moving at constant velocity.

    ``constants`` is :func:`flow_constants` of ``p``, ``connections`` the tuple of
    :func:`valve_connections` for the substep. Updates s
    in place; adds time_step-weighted flows to ``out.cap_mass_flow``, ``out.rod_mass_flow``
    and ``out.supply_mass_flow`` (callers divide by the step length). Returns the mass
    drawn from the supply [kg]. The two halves are :func:`heun_first_rates` and
    :func:`heun_finish`, for callers that interleave several actuators' substeps.
    """
    first = heun_first_rates(p, constants, s, position, velocity, connections)
    return heun_finish(p, constants, s, position, velocity, time_step, connections, out, first)


@compiled(inline=True)
def heun_first_rates(p, constants, s, position, velocity, connections):
    """The rates of :func:`pneumatic_rates` at the substep's start (Heun's first stage)."""
    cap_source, cap_conductance, rod_source, rod_conductance = connections
    return pneumatic_rates(
        p,
        constants,
        s.cap_pressure,
        s.rod_pressure,
        s.cap_mass,
        s.rod_mass,
        position,
        velocity,
        cap_source,
        cap_conductance,
        rod_source,
        rod_conductance,
    )


@compiled(inline=True)
def heun_finish(p, constants, s, position, velocity, time_step, connections, out, first):
    """The rest of :func:`heun_pneumatics` from its first-stage rates ``first``
    (:func:`heun_first_rates`): the predictor, the rates there, the corrected state and
    the outputs. Returns the mass drawn from the supply [kg]."""
    cap_source, cap_conductance, rod_source, rod_conductance = connections
    dpc1, dpr1, fc1, fr1, draw1 = first
    pc = s.cap_pressure
    pr = s.rod_pressure
    mc = s.cap_mass
    mr = s.rod_mass
    h = time_step
    pc_pred = max(pc + h * dpc1, 1.0)
    pr_pred = max(pr + h * dpr1, 1.0)
    mc_pred = max(mc + h * fc1, 1e-12)
    mr_pred = max(mr + h * fr1, 1e-12)
    dpc2, dpr2, fc2, fr2, draw2 = pneumatic_rates(
        p,
        constants,
        pc_pred,
        pr_pred,
        mc_pred,
        mr_pred,
        position + h * velocity,
        velocity,
        cap_source,
        cap_conductance,
        rod_source,
        rod_conductance,
    )
    s.cap_pressure = max(pc + 0.5 * h * (dpc1 + dpc2), 1.0)
    s.rod_pressure = max(pr + 0.5 * h * (dpr1 + dpr2), 1.0)
    s.cap_mass = max(mc + 0.5 * h * (fc1 + fc2), 1e-12)
    s.rod_mass = max(mr + 0.5 * h * (fr1 + fr2), 1e-12)
    drawn = 0.5 * h * (draw1 + draw2)
    s.air_consumed += drawn
    out.cap_mass_flow += 0.5 * h * (fc1 + fc2)
    out.rod_mass_flow += 0.5 * h * (fr1 + fr2)
    out.supply_mass_flow += drawn
    return drawn


@compiled
def pneumatic_force_of(p, s):
    """Pneumatic force of actuator ``p`` in chamber state ``s`` [N] (eq 4.1.11, positive
    extends the piston; no friction)."""
    return piston_force(
        s.cap_pressure,
        s.rod_pressure,
        p.atmospheric_pressure,
        p.cap_area,
        p.rod_area,
        p.rod_cross_section,
    )


@compiled
def friction_of(p, velocity, bristle):
    """Friction force of actuator ``p`` at a velocity and bristle deflection [N]."""
    return friction_force(
        p.friction_model,
        velocity,
        bristle,
        p.static_force,
        p.coulomb_force,
        p.viscous_coefficient,
        p.stribeck_velocity,
        p.stribeck_exponent,
        p.tanh_coefficient,
        p.damping_coefficient,
        p.bristle_stiffness,
        p.bristle_damping,
    )


@compiled
def friction_slope_of(p, velocity, bristle):
    """Dissipative slope dF/dv of actuator ``p``'s friction law [N s/m] (see
    :func:`pneumaquad.core.physics.friction.friction_damping`)."""
    return friction_damping(
        p.friction_model,
        velocity,
        p.static_force,
        p.coulomb_force,
        p.viscous_coefficient,
        p.stribeck_velocity,
        p.stribeck_exponent,
        p.tanh_coefficient,
        p.damping_coefficient,
        p.bristle_stiffness,
        p.bristle_damping,
        bristle,
    )


@compiled
def friction_and_slope_of(p, velocity, bristle):
    """Friction force [N] and dissipative slope [N s/m] of actuator ``p`` at one velocity
    and bristle deflection: :func:`friction_of` and :func:`friction_slope_of` together,
    the Stribeck-tanh law's curve and tanh evaluated once
    (:func:`pneumaquad.core.physics.friction.stribeck_tanh_force_and_slope`)."""
    if p.friction_model == FRICTION_STRIBECK_TANH:
        if abs(velocity) < p.stribeck_flat_velocity:  # g(v) is Fs, bit for bit
            curve = p.coulomb_force + (p.static_force - p.coulomb_force)
        else:
            curve = stribeck_curve(velocity, p.static_force, p.coulomb_force,
                                   p.stribeck_velocity, p.stribeck_exponent)
        return stribeck_tanh_force_and_slope_of_curve(
            curve, velocity, p.viscous_coefficient, p.tanh_coefficient)
    return friction_of(p, velocity, bristle), friction_slope_of(p, velocity, bristle)


@compiled
def advance_bristle(p, bristle, velocity, time_step):
    """LuGre bristle deflection after a step at constant velocity (unchanged for others)."""
    if p.friction_model != FRICTION_LUGRE:
        return bristle
    g = stribeck_curve(
        velocity, p.static_force, p.coulomb_force, p.stribeck_velocity, p.stribeck_exponent
    )
    return lugre_bristle_update(bristle, velocity, time_step, p.bristle_stiffness, g)


@compiled
def finish_outputs(p, s, position, control_step, out):
    """Turn accumulated flows into means and fill forces and temperatures at step end."""
    out.cap_mass_flow /= control_step
    out.rod_mass_flow /= control_step
    out.supply_mass_flow /= control_step
    state_outputs(p, s, position, out)


@compiled
def state_outputs(p, s, position, out):
    """Pneumatic force [N] (eq 4.1.11) and chamber temperatures [K] of the state ``s`` with
    the piston at ``position`` [m], into ``out``."""
    out.pneumatic_force = pneumatic_force_of(p, s)
    out.cap_temperature = chamber_temperature(
        s.cap_pressure,
        chamber_volume_cap(position, p.cap_area, p.cap_dead_length),
        s.cap_mass,
        p.gas_constant,
    )
    out.rod_temperature = chamber_temperature(
        s.rod_pressure,
        chamber_volume_rod(position, p.stroke, p.rod_area, p.rod_dead_length),
        s.rod_mass,
        p.gas_constant,
    )


@compiled
def draw_from_tank(supply, drawn_mass):
    """Isothermal tank: remove the drawn mass, dP = -R·T·dm/V."""
    supply.drawn_mass += drawn_mass
    if supply.model == SUPPLY_TANK:
        gas = supply.gas_constant * supply.tank_temperature
        supply.tank_pressure -= gas * drawn_mass / supply.tank_volume
        supply.tank_pressure = max(supply.tank_pressure, 0.0)


@compiled
def clear_outputs(out):
    """Zero every field of an output record (ACTUATOR_OUTPUT_DTYPE)."""
    out.cap_mass_flow = 0.0
    out.rod_mass_flow = 0.0
    out.pneumatic_force = 0.0
    out.friction_force = 0.0
    out.end_stop_force = 0.0
    out.cap_temperature = 0.0
    out.rod_temperature = 0.0
    out.supply_mass_flow = 0.0


@compiled
def begin_control_step(p, s, out, command, supply):
    """Reset an actuator's outputs and set up its valve for a control step.

    Returns (target centered voltage [V], whether the spool lags, supply pressure [Pa],
    valve connections). Without a spool lag the spool jumps to the target and the valve
    map is evaluated here once for the whole step.
    """
    clear_outputs(out)
    supply_pressure = supply_pressure_now(p, supply)
    target = centered_voltage(command, p.offset_voltage, p.min_voltage, p.max_voltage)
    lagging = p.spool_time_constant > 0.0
    if not lagging:
        s.spool_voltage = target
    return target, lagging, supply_pressure, valve_connections(p, s.spool_voltage, supply_pressure)


@compiled
def substep_connections(p, s, target, lagging, supply_pressure, connections, time_step):
    """Valve connections for the next substep: moved with the spool lag, else unchanged."""
    if not lagging:
        return connections
    s.spool_voltage = spool_update(p, s.spool_voltage, target, time_step)
    return valve_connections(p, s.spool_voltage, supply_pressure)
