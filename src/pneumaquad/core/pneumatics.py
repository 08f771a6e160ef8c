"""Per-actuator pneumatic building blocks of the compiled kernels.

What one actuator's chambers do over a substep: which pressure each port sees and
through what conductance (valve map), the port mass flows, the chamber pressure and mass
rates (eq 4.1.7, 4.1.10), a Heun substep of those states, the spool lag, the LuGre
bristle update, the supply draw and the end-of-step outputs. :mod:`pneumaquad.core.kernel`
loops these over actuators and substeps.
"""

import math

from pneumaquad.core.jit import compiled
from pneumaquad.core.layout import (
    AREA_LINEAR,
    FLOW_ISO6358,
    INPUT_SWITCHED,
    N_OUTPUTS,
    O_CAP_FLOW,
    O_CAP_TEMPERATURE,
    O_PNEUMATIC_FORCE,
    O_ROD_FLOW,
    O_ROD_TEMPERATURE,
    O_SUPPLY_DRAW,
    P_AREA_CURVE,
    P_BORE,
    P_C1,
    P_C2,
    P_CAP_AREA,
    P_CAP_DEAD,
    P_CAP_HIGH_CUTOFF,
    P_CAP_LOW_CUTOFF,
    P_CAP_POLY_NEG,
    P_CAP_POLY_POS,
    P_CD_CAP,
    P_CD_ROD,
    P_CP,
    P_CRITICAL,
    P_CV,
    P_DAMPING,
    P_EXPONENT,
    P_FC,
    P_FLOW_FORM,
    P_FRICTION_MODEL,
    P_FS,
    P_HEAT_TRANSFER,
    P_INPUT_PRESSURE,
    P_ISO_B,
    P_ISO_CONDUCTANCE,
    P_ISO_LEAK_CONDUCTANCE,
    P_K,
    P_KTANH,
    P_LAMINAR,
    P_OFFSET,
    P_PATM,
    P_PE,
    P_POLYTROPIC_N,
    P_PS,
    P_R,
    P_ROD_AREA,
    P_ROD_DEAD,
    P_ROD_HIGH_CUTOFF,
    P_ROD_LOW_CUTOFF,
    P_ROD_POLY_NEG,
    P_ROD_POLY_POS,
    P_ROD_SECTION,
    P_SIGMA0,
    P_SIGMA1,
    P_SIMPLE_FULL_SCALE,
    P_SIMPLE_LEAK_AREA,
    P_SIMPLE_MAX_AREA,
    P_SPOOL_TAU,
    P_STROKE,
    P_THERMO_MODEL,
    P_TS,
    P_UMAX,
    P_UMIN,
    P_VALVE_MODEL,
    P_VS,
    P_WALL_TEMPERATURE,
    S_AIR_CONSUMED,
    S_CAP_MASS,
    S_CAP_PRESSURE,
    S_ROD_MASS,
    S_ROD_PRESSURE,
    S_SPOOL,
    SUPPLY_DRAWN_MASS,
    SUPPLY_GAS_CONSTANT,
    SUPPLY_MODEL,
    SUPPLY_TANK_PRESSURE,
    SUPPLY_TANK_TEMPERATURE,
    SUPPLY_TANK_VOLUME,
    VALVE_SIMPLE,
)
from pneumaquad.core.physics.chamber import (
    THERMO_HEAT_TRANSFER,
    chamber_pressure_rate,
    chamber_temperature,
    chamber_volume_cap,
    chamber_volume_rod,
)
from pneumaquad.core.physics.force import piston_force
from pneumaquad.core.physics.friction import (
    FRICTION_LUGRE,
    friction_damping,
    friction_force,
    lugre_bristle_update,
    stribeck_curve,
)
from pneumaquad.core.physics.orifice import (
    area_to_sonic_conductance,
    iso6358_flux,
    laminar_temperature,
    orifice_flux,
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
    if supply[SUPPLY_MODEL] == 1.0:
        return min(p[P_PS], supply[SUPPLY_TANK_PRESSURE])
    return p[P_PS]


@compiled
def valve_connections(p, centered: float, supply_pressure: float):
    """What each chamber is connected to at a centered valve voltage.

    Returns (cap source pressure [Pa], cap conductance, rod source pressure [Pa], rod
    conductance). Conductance is an effective area cd·A [m^2] for the orifice form and a
    sonic conductance [m^3/(s Pa)] for the ISO 6358 form. Simple valve: positive voltage
    connects the cap to supply and the rod to exhaust (thesis Fig. 18). Underlapped valve:
    each port sees the tanh input pressure of eq 4.2.7 through its polynomial area; either
    part can be swapped for the simple valve's (``P_INPUT_PRESSURE`` switched supply/exhaust,
    ``P_AREA_CURVE`` linear area), the separate rows of thesis Table 3.
    """
    exhaust = p[P_PE]
    iso = p[P_FLOW_FORM] == FLOW_ISO6358
    if p[P_VALVE_MODEL] == VALVE_SIMPLE:
        if iso:
            span = abs(centered) / p[P_SIMPLE_FULL_SCALE]
            cap_conductance = p[P_ISO_CONDUCTANCE] * span + p[P_ISO_LEAK_CONDUCTANCE]
            rod_conductance = cap_conductance
        else:
            area = simple_valve_area(
                centered, p[P_SIMPLE_MAX_AREA], p[P_SIMPLE_LEAK_AREA], p[P_SIMPLE_FULL_SCALE]
            )
            cap_conductance = p[P_CD_CAP] * area
            rod_conductance = p[P_CD_ROD] * area
        if centered >= 0.0:
            return supply_pressure, cap_conductance, exhaust, rod_conductance
        return exhaust, cap_conductance, supply_pressure, rod_conductance
    if p[P_INPUT_PRESSURE] == INPUT_SWITCHED:
        # the simple valve's plain supply/exhaust pressures (thesis Table 3 ablation)
        if centered >= 0.0:
            cap_source, rod_source = supply_pressure, exhaust
        else:
            cap_source, rod_source = exhaust, supply_pressure
    else:
        cap_source = input_pressure(
            centered, supply_pressure, exhaust, p[P_CAP_HIGH_CUTOFF], p[P_CAP_LOW_CUTOFF]
        )
        rod_source = input_pressure(
            centered, supply_pressure, exhaust, p[P_ROD_HIGH_CUTOFF], p[P_ROD_LOW_CUTOFF]
        )
    if p[P_AREA_CURVE] == AREA_LINEAR:
        # the simple valve's linear slot area (thesis Table 3 ablation)
        area = simple_valve_area(
            centered, p[P_SIMPLE_MAX_AREA], p[P_SIMPLE_LEAK_AREA], p[P_SIMPLE_FULL_SCALE]
        )
        cap_area = p[P_CD_CAP] * area
        rod_area = p[P_CD_ROD] * area
    else:
        cap_area = polynomial_area(
            centered, p[P_CAP_POLY_NEG : P_CAP_POLY_NEG + 5],
            p[P_CAP_POLY_POS : P_CAP_POLY_POS + 5],
        )
        rod_area = polynomial_area(
            centered, p[P_ROD_POLY_NEG : P_ROD_POLY_NEG + 5],
            p[P_ROD_POLY_POS : P_ROD_POLY_POS + 5],
        )
    if iso:
        return (
            cap_source,
            area_to_sonic_conductance(cap_area, p[P_C2]),
            rod_source,
            area_to_sonic_conductance(rod_area, p[P_C2]),
        )
    return cap_source, cap_area, rod_source, rod_area


@compiled
def flow_temperature(p, source_pressure, pressure, temperature):
    """Temperature of the air crossing a port [K]: supply temperature when filling, the
    chamber's when emptying, blended to their mean near equal pressures (see
    :func:`pneumaquad.core.physics.orifice.laminar_temperature`), so that flow and energy
    balance stay smooth through zero flow."""
    if source_pressure >= pressure:
        return laminar_temperature(source_pressure, pressure, p[P_TS], temperature, p[P_LAMINAR])
    return laminar_temperature(pressure, source_pressure, temperature, p[P_TS], p[P_LAMINAR])


@compiled
def port_flow(p, conductance, source_pressure, pressure, crossing_temperature):
    """Mass flow into a chamber from its valve port [kg/s].

    The same law as :func:`pneumaquad.core.physics.orifice.orifice_mass_flow` (or the ISO 6358
    form), with the temperature of the crossing air from :func:`flow_temperature` passed
    in, since the energy balance needs it too.
    """
    if source_pressure >= pressure:
        upstream, downstream, sign = source_pressure, pressure, 1.0
    else:
        upstream, downstream, sign = pressure, source_pressure, -1.0
    if p[P_FLOW_FORM] == FLOW_ISO6358:
        return (
            sign
            * conductance
            * iso6358_flux(upstream, downstream, crossing_temperature, p[P_ISO_B], p[P_LAMINAR])
        )
    return (
        sign
        * conductance
        * orifice_flux(
            upstream,
            downstream,
            crossing_temperature,
            p[P_K],
            p[P_C1],
            p[P_C2],
            p[P_CRITICAL],
            p[P_LAMINAR],
        )
    )


@compiled
def chamber_rate(p, pressure, temperature, volume, volume_rate, flow_in, flow_temp, wall_area):
    """dP/dt of one chamber (eq 4.1.10) given its temperature and net inflow."""
    return chamber_pressure_rate(
        pressure,
        volume,
        volume_rate,
        flow_in,
        flow_temp,
        temperature,
        wall_area,
        p[P_K],
        p[P_R],
        p[P_CP],
        int(p[P_THERMO_MODEL]),
        p[P_POLYTROPIC_N],
        p[P_HEAT_TRANSFER],
        p[P_WALL_TEMPERATURE],
    )


@compiled
def pneumatic_rates(
    p,
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

    Returns (dP_cap/dt [Pa/s], dP_rod/dt [Pa/s], m_dot_cap [kg/s], m_dot_rod [kg/s],
    supply draw [kg/s]).
    """
    cap_volume = chamber_volume_cap(position, p[P_CAP_AREA], p[P_CAP_DEAD])
    rod_volume = chamber_volume_rod(position, p[P_STROKE], p[P_ROD_AREA], p[P_ROD_DEAD])
    cap_temperature = chamber_temperature(cap_pressure, cap_volume, cap_mass, p[P_R])
    rod_temperature = chamber_temperature(rod_pressure, rod_volume, rod_mass, p[P_R])
    cap_crossing = flow_temperature(p, cap_source, cap_pressure, cap_temperature)
    rod_crossing = flow_temperature(p, rod_source, rod_pressure, rod_temperature)
    cap_flow = port_flow(p, cap_conductance, cap_source, cap_pressure, cap_crossing)
    rod_flow = port_flow(p, rod_conductance, rod_source, rod_pressure, rod_crossing)
    cap_wall = 0.0
    rod_wall = 0.0
    if p[P_THERMO_MODEL] == THERMO_HEAT_TRANSFER:
        end_faces = 0.5 * math.pi * p[P_BORE] * p[P_BORE]
        cap_wall = end_faces + math.pi * p[P_BORE] * cap_volume / p[P_CAP_AREA]
        rod_wall = end_faces + math.pi * p[P_BORE] * rod_volume / p[P_ROD_AREA]
    cap_rate = chamber_rate(
        p,
        cap_pressure,
        cap_temperature,
        cap_volume,
        p[P_CAP_AREA] * velocity,
        cap_flow,
        cap_crossing,
        cap_wall,
    )
    rod_rate = chamber_rate(
        p,
        rod_pressure,
        rod_temperature,
        rod_volume,
        -p[P_ROD_AREA] * velocity,
        rod_flow,
        rod_crossing,
        rod_wall,
    )
    draw = 0.0
    exhaust = p[P_PE]
    if cap_flow > 0.0 and cap_source > exhaust:
        draw += cap_flow
    if rod_flow > 0.0 and rod_source > exhaust:
        draw += rod_flow
    return cap_rate, rod_rate, cap_flow, rod_flow, draw


@compiled
def spool_update(p, spool: float, target: float, time_step: float) -> float:
    """First-order spool lag (valve bandwidth) advanced exactly over a step (tau > 0)."""
    tau = p[P_SPOOL_TAU]
    return target + (spool - target) * math.exp(-time_step / tau)


@compiled
def heun_pneumatics(p, s, position, velocity, time_step, connections, out):
    """One Heun substep of the chamber states with the piston moving at constant velocity.

    ``connections`` is the tuple of :func:`valve_connections` for the substep. Updates s
    in place; adds time_step-weighted flows to out[O_CAP_FLOW], out[O_ROD_FLOW] and
    out[O_SUPPLY_DRAW] (callers divide by the step length).
    """
    cap_source, cap_conductance, rod_source, rod_conductance = connections
    pc = s[S_CAP_PRESSURE]
    pr = s[S_ROD_PRESSURE]
    mc = s[S_CAP_MASS]
    mr = s[S_ROD_MASS]
    dpc1, dpr1, fc1, fr1, draw1 = pneumatic_rates(
        p,
        pc,
        pr,
        mc,
        mr,
        position,
        velocity,
        cap_source,
        cap_conductance,
        rod_source,
        rod_conductance,
    )
    h = time_step
    pc_pred = max(pc + h * dpc1, 1.0)
    pr_pred = max(pr + h * dpr1, 1.0)
    mc_pred = max(mc + h * fc1, 1e-12)
    mr_pred = max(mr + h * fr1, 1e-12)
    dpc2, dpr2, fc2, fr2, draw2 = pneumatic_rates(
        p,
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
    s[S_CAP_PRESSURE] = max(pc + 0.5 * h * (dpc1 + dpc2), 1.0)
    s[S_ROD_PRESSURE] = max(pr + 0.5 * h * (dpr1 + dpr2), 1.0)
    s[S_CAP_MASS] = max(mc + 0.5 * h * (fc1 + fc2), 1e-12)
    s[S_ROD_MASS] = max(mr + 0.5 * h * (fr1 + fr2), 1e-12)
    drawn = 0.5 * h * (draw1 + draw2)
    s[S_AIR_CONSUMED] += drawn
    out[O_CAP_FLOW] += 0.5 * h * (fc1 + fc2)
    out[O_ROD_FLOW] += 0.5 * h * (fr1 + fr2)
    out[O_SUPPLY_DRAW] += drawn
    return drawn


@compiled
def friction_of(p, velocity, bristle):
    """Friction force of actuator row p at a velocity and bristle deflection [N]."""
    return friction_force(
        int(p[P_FRICTION_MODEL]),
        velocity,
        bristle,
        p[P_FS],
        p[P_FC],
        p[P_CV],
        p[P_VS],
        p[P_EXPONENT],
        p[P_KTANH],
        p[P_DAMPING],
        p[P_SIGMA0],
        p[P_SIGMA1],
    )


@compiled
def friction_slope_of(p, velocity, bristle):
    """Dissipative slope dF/dv of actuator row p's friction law [N s/m] (see
    :func:`pneumaquad.core.physics.friction.friction_damping`)."""
    return friction_damping(
        int(p[P_FRICTION_MODEL]),
        velocity,
        p[P_FS],
        p[P_FC],
        p[P_CV],
        p[P_VS],
        p[P_EXPONENT],
        p[P_KTANH],
        p[P_DAMPING],
        p[P_SIGMA0],
        p[P_SIGMA1],
        bristle,
    )


@compiled
def advance_bristle(p, bristle, velocity, time_step):
    """LuGre bristle deflection after a step at constant velocity (unchanged for others)."""
    if int(p[P_FRICTION_MODEL]) != FRICTION_LUGRE:
        return bristle
    g = stribeck_curve(velocity, p[P_FS], p[P_FC], p[P_VS], p[P_EXPONENT])
    return lugre_bristle_update(bristle, velocity, time_step, p[P_SIGMA0], g)


@compiled
def finish_outputs(p, s, position, control_step, out):
    """Turn accumulated flows into means and fill forces and temperatures at step end."""
    out[O_CAP_FLOW] /= control_step
    out[O_ROD_FLOW] /= control_step
    out[O_SUPPLY_DRAW] /= control_step
    state_outputs(p, s, position, out)


@compiled
def state_outputs(p, s, position, out):
    """Pneumatic force [N] (eq 4.1.11) and chamber temperatures [K] of the state ``s`` with
    the piston at ``position`` [m], into ``out``."""
    out[O_PNEUMATIC_FORCE] = piston_force(
        s[S_CAP_PRESSURE],
        s[S_ROD_PRESSURE],
        p[P_PATM],
        p[P_CAP_AREA],
        p[P_ROD_AREA],
        p[P_ROD_SECTION],
    )
    out[O_CAP_TEMPERATURE] = chamber_temperature(
        s[S_CAP_PRESSURE],
        chamber_volume_cap(position, p[P_CAP_AREA], p[P_CAP_DEAD]),
        s[S_CAP_MASS],
        p[P_R],
    )
    out[O_ROD_TEMPERATURE] = chamber_temperature(
        s[S_ROD_PRESSURE],
        chamber_volume_rod(position, p[P_STROKE], p[P_ROD_AREA], p[P_ROD_DEAD]),
        s[S_ROD_MASS],
        p[P_R],
    )


@compiled
def draw_from_tank(supply, drawn_mass):
    """Isothermal tank: remove the drawn mass, dP = -R·T·dm/V."""
    supply[SUPPLY_DRAWN_MASS] += drawn_mass
    if supply[SUPPLY_MODEL] == 1.0:
        gas = supply[SUPPLY_GAS_CONSTANT] * supply[SUPPLY_TANK_TEMPERATURE]
        supply[SUPPLY_TANK_PRESSURE] -= gas * drawn_mass / supply[SUPPLY_TANK_VOLUME]
        supply[SUPPLY_TANK_PRESSURE] = max(supply[SUPPLY_TANK_PRESSURE], 0.0)


@compiled
def begin_control_step(p, s, out, command, supply):
    """Reset an actuator's outputs and set up its valve for a control step.

    Returns (target centered voltage [V], whether the spool lags, supply pressure [Pa],
    valve connections). Without a spool lag the spool jumps to the target and the valve
    map is evaluated here once for the whole step.
    """
    for column in range(N_OUTPUTS):
        out[column] = 0.0
    supply_pressure = supply_pressure_now(p, supply)
    target = centered_voltage(command, p[P_OFFSET], p[P_UMIN], p[P_UMAX])
    lagging = p[P_SPOOL_TAU] > 0.0
    if not lagging:
        s[S_SPOOL] = target
    return target, lagging, supply_pressure, valve_connections(p, s[S_SPOOL], supply_pressure)


@compiled
def substep_connections(p, s, target, lagging, supply_pressure, connections, time_step):
    """Valve connections for the next substep: moved with the spool lag, else unchanged."""
    if not lagging:
        return connections
    s[S_SPOOL] = spool_update(p, s[S_SPOOL], target, time_step)
    return valve_connections(p, s[S_SPOOL], supply_pressure)
