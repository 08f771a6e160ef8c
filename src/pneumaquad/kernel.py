"""Compiled kernels: the pneumatic state of N actuators advanced by one control step.

Two entry points share every physics function of :mod:`pneumaquad.physics`:

* :func:`step_actuators` — pistons driven from outside (the robot: MuJoCo gives position
  and velocity, the kernel returns forces). Position moves linearly over the step.
* :func:`step_rigs` — N independent single-DoF rigs, pneumatics and piston mechanics
  together (cylinder + load mass, gravity, end stops, friction).

Both integrate the chamber pressures and masses with Heun's method (explicit RK2) over
``substeps`` internal steps. The LuGre bristle state and the spool lag are advanced with
exact exponential updates. In the rig, the piston velocity is advanced linearly implicitly
(friction slope and end-stop stiffness on the left-hand side), so the stiff friction laws
near zero velocity stay stable, and the Coulomb models get an exact stick/slip step.
"""

import math

import numpy as np

from pneumaquad.jit import compiled
from pneumaquad.layout import (
    FLOW_ISO6358,
    N_OUTPUTS,
    O_CAP_FLOW,
    O_CAP_TEMPERATURE,
    O_END_STOP_FORCE,
    O_FRICTION_FORCE,
    O_PNEUMATIC_FORCE,
    O_ROD_FLOW,
    O_ROD_TEMPERATURE,
    O_SUPPLY_DRAW,
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
    P_GRAVITY_FORCE,
    P_HEAT_TRANSFER,
    P_ISO_B,
    P_ISO_CONDUCTANCE,
    P_ISO_LEAK_CONDUCTANCE,
    P_K,
    P_KTANH,
    P_LAMINAR,
    P_MOVING_MASS,
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
    P_SPACER,
    P_SPOOL_TAU,
    P_STOP_DAMPING,
    P_STOP_STIFFNESS,
    P_STROKE,
    P_THERMO_MODEL,
    P_TS,
    P_UMAX,
    P_UMIN,
    P_VALVE_MODEL,
    P_VS,
    P_WALL_TEMPERATURE,
    S_AIR_CONSUMED,
    S_BRISTLE,
    S_CAP_MASS,
    S_CAP_PRESSURE,
    S_POSITION,
    S_ROD_MASS,
    S_ROD_PRESSURE,
    S_SPOOL,
    S_VELOCITY,
    SUPPLY_DRAWN_MASS,
    SUPPLY_GAS_CONSTANT,
    SUPPLY_MODEL,
    SUPPLY_TANK_PRESSURE,
    SUPPLY_TANK_TEMPERATURE,
    SUPPLY_TANK_VOLUME,
    VALVE_SIMPLE,
)
from pneumaquad.physics.chamber import (
    THERMO_HEAT_TRANSFER,
    chamber_pressure_rate,
    chamber_temperature,
    chamber_volume_cap,
    chamber_volume_rod,
)
from pneumaquad.physics.force import end_stop_force, piston_force
from pneumaquad.physics.friction import (
    FRICTION_COULOMB,
    FRICTION_COULOMB_VISCOUS,
    FRICTION_LUGRE,
    friction_damping,
    friction_force,
    lugre_bristle_update,
    stribeck_curve,
)
from pneumaquad.physics.orifice import (
    area_to_sonic_conductance,
    iso6358_mass_flow,
    laminar_temperature,
    orifice_mass_flow,
)
from pneumaquad.physics.valve import (
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
    each port sees the tanh input pressure of eq 4.2.7 through its polynomial area.
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
    cap_source = input_pressure(
        centered, supply_pressure, exhaust, p[P_CAP_HIGH_CUTOFF], p[P_CAP_LOW_CUTOFF]
    )
    rod_source = input_pressure(
        centered, supply_pressure, exhaust, p[P_ROD_HIGH_CUTOFF], p[P_ROD_LOW_CUTOFF]
    )
    cap_area = polynomial_area(
        centered, p[P_CAP_POLY_NEG : P_CAP_POLY_NEG + 5], p[P_CAP_POLY_POS : P_CAP_POLY_POS + 5]
    )
    rod_area = polynomial_area(
        centered, p[P_ROD_POLY_NEG : P_ROD_POLY_NEG + 5], p[P_ROD_POLY_POS : P_ROD_POLY_POS + 5]
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
def port_flow(p, conductance: float, source_pressure: float, pressure: float, temperature: float):
    """Mass flow into a chamber from its valve port [kg/s] (air enters at supply temperature)."""
    if p[P_FLOW_FORM] == FLOW_ISO6358:
        return iso6358_mass_flow(
            conductance,
            source_pressure,
            pressure,
            p[P_TS],
            temperature,
            p[P_ISO_B],
            p[P_LAMINAR],
        )
    return orifice_mass_flow(
        conductance,
        source_pressure,
        pressure,
        p[P_TS],
        temperature,
        p[P_K],
        p[P_C1],
        p[P_C2],
        p[P_CRITICAL],
        p[P_LAMINAR],
    )


@compiled
def flow_temperature(p, source_pressure, pressure, temperature):
    """Temperature of the air crossing a port [K]: supply temperature when filling, the
    chamber's when emptying, blended to their mean near equal pressures (see
    :func:`pneumaquad.physics.orifice.laminar_temperature`), so that the energy balance
    stays smooth through zero flow."""
    if source_pressure >= pressure:
        return laminar_temperature(source_pressure, pressure, p[P_TS], temperature, p[P_LAMINAR])
    return laminar_temperature(pressure, source_pressure, temperature, p[P_TS], p[P_LAMINAR])


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
    cap_flow = port_flow(p, cap_conductance, cap_source, cap_pressure, cap_temperature)
    rod_flow = port_flow(p, rod_conductance, rod_source, rod_pressure, rod_temperature)
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
        flow_temperature(p, cap_source, cap_pressure, cap_temperature),
        cap_wall,
    )
    rod_rate = chamber_rate(
        p,
        rod_pressure,
        rod_temperature,
        rod_volume,
        -p[P_ROD_AREA] * velocity,
        rod_flow,
        flow_temperature(p, rod_source, rod_pressure, rod_temperature),
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


@compiled
def step_actuators(
    params, state, commands, positions, velocities, control_step, substeps, supply, outputs
):
    """Advance N externally driven actuators by one control step.

    Parameters
    ----------
    params : ndarray (N, N_PARAMETERS)
        Packed parameters (:func:`pneumaquad.actuator.pack_parameters`).
    state : ndarray (N, N_STATES)
        Chamber states, updated in place. S_POSITION and S_VELOCITY are overwritten with
        the inputs advanced over the step.
    commands : ndarray (N,)
        Valve voltages held over the step [V].
    positions, velocities : ndarray (N,)
        Piston extension [m] and velocity [m/s] at the start of the step; the position is
        moved linearly over the step.
    control_step : float
        Step length [s].
    substeps : int
        Heun substeps per control step.
    supply : ndarray (N_SUPPLY,)
        Shared supply state (ideal or tank), updated in place once per step.
    outputs : ndarray (N, N_OUTPUTS)
        Filled with mean flows, end-of-step forces (pneumatic and friction, the latter at
        the given velocity) and temperatures.
    """
    count = params.shape[0]
    h = control_step / substeps
    total_drawn = 0.0
    for index in range(count):
        p = params[index]
        s = state[index]
        out = outputs[index]
        target, lagging, supply_pressure, connections = begin_control_step(
            p, s, out, commands[index], supply
        )
        position = positions[index]
        velocity = velocities[index]
        for _ in range(substeps):
            connections = substep_connections(
                p, s, target, lagging, supply_pressure, connections, h
            )
            total_drawn += heun_pneumatics(p, s, position, velocity, h, connections, out)
            position += h * velocity
        s[S_BRISTLE] = advance_bristle(p, s[S_BRISTLE], velocity, control_step)
        s[S_POSITION] = position
        s[S_VELOCITY] = velocity
        finish_outputs(p, s, position, control_step, out)
        out[O_FRICTION_FORCE] = friction_of(p, velocity, s[S_BRISTLE])
    draw_from_tank(supply, total_drawn)


@compiled
def rig_mechanics_substep(p, s, time_step, out):
    """Advance piston position and velocity of a single-DoF rig by one substep.

    Linearly implicit Euler in velocity: m·(v1 - v0) = h·(F + dF/dx·h·v1 + dF/dv·(v1 - v0)),
    x1 = x0 + h·v1, with the end-stop stiffness and the dissipative friction slope on the
    left-hand side. Coulomb models take an exact stick/slip step: if the dry-friction force
    needed to stop the piston within the step is below breakaway (Fs from rest in the
    Coulomb-viscous model of eq 4.2.4, Fc otherwise), the piston stops.
    """
    h = time_step
    x = s[S_POSITION]
    v = s[S_VELOCITY]
    mass = p[P_MOVING_MASS]
    force = (
        piston_force(
            s[S_CAP_PRESSURE],
            s[S_ROD_PRESSURE],
            p[P_PATM],
            p[P_CAP_AREA],
            p[P_ROD_AREA],
            p[P_ROD_SECTION],
        )
        + p[P_GRAVITY_FORCE]
    )
    stop = end_stop_force(x, v, p[P_STROKE], p[P_STOP_STIFFNESS], p[P_STOP_DAMPING])
    model = int(p[P_FRICTION_MODEL])
    dry_model = model in (FRICTION_COULOMB, FRICTION_COULOMB_VISCOUS)
    resting_on_stop = dry_model and v == 0.0 and stop != 0.0
    if resting_on_stop:
        # A piston stuck on a stop: the rigid stop reacts only as much as the load presses
        # into it, and stores nothing, so when the load pulls away the contact spring's
        # penetration is dropped and friction alone holds the piston (breakaway at Fs).
        stop = max(0.0, -force) if stop > 0.0 else min(0.0, -force)
        if stop == 0.0:
            x = min(max(x, 0.0), p[P_STROKE])
    stiffness = 0.0
    stop_damping = 0.0
    if stop != 0.0 and not resting_on_stop:
        stiffness = p[P_STOP_STIFFNESS]
        stop_damping = p[P_STOP_DAMPING]
    damping = friction_damping(
        model,
        v,
        p[P_FS],
        p[P_FC],
        p[P_CV],
        p[P_VS],
        p[P_EXPONENT],
        p[P_KTANH],
        p[P_DAMPING],
        p[P_SIGMA0],
        p[P_SIGMA1],
        s[S_BRISTLE],
    )
    effective_mass = mass + h * (damping + stop_damping) + h * h * stiffness
    if dry_model:
        viscous = p[P_CV] if model == FRICTION_COULOMB_VISCOUS else 0.0
        free = v + h * (force + stop - viscous * v - h * stiffness * v) / effective_mass
        needed = effective_mass * free / h
        breakaway = p[P_FS] if (v == 0.0 and model == FRICTION_COULOMB_VISCOUS) else p[P_FC]
        if abs(needed) <= breakaway:
            v_new = 0.0
            dry = needed
        else:
            dry = p[P_FC] if free > 0.0 else -p[P_FC]
            v_new = free - h * dry / effective_mass
        friction = dry + viscous * v_new
    else:
        s[S_BRISTLE] = advance_bristle(p, s[S_BRISTLE], v, h)
        friction = friction_of(p, v, s[S_BRISTLE])
        v_new = v + h * (force + stop - friction - h * stiffness * v) / effective_mass
        if model != FRICTION_LUGRE and v_new * v < 0.0:
            # The friction force, taken at the old velocity, overshot through zero. A law
            # of velocity alone is dissipative (F·v >= 0), so redo the step with its secant
            # F/v as the implicit damping: without this, just past the Stribeck hump (where
            # the tangent is almost zero) the velocity flips sign every substep.
            secant = friction / v
            if secant > damping:
                effective_mass += h * (secant - damping)
                v_new = v + h * (force + stop - friction - h * stiffness * v) / effective_mass
    s[S_VELOCITY] = v_new
    s[S_POSITION] = x + h * v_new
    out[O_FRICTION_FORCE] = friction
    out[O_END_STOP_FORCE] = stop


@compiled
def step_rigs(params, state, commands, control_step, substeps, supply, outputs):
    """Advance N single-DoF rigs (cylinder + load) by one control step.

    Parameters as in :func:`step_actuators`, without external positions: each rig's
    S_POSITION and S_VELOCITY are its own states. Per substep the chamber states take a
    Heun step with the piston moving at its current velocity, then the piston takes a
    linearly implicit step with the new pressures (:func:`rig_mechanics_substep`). In
    spacer mode the piston stays at full extension and the end-stop force is the load
    the spacer carries.
    """
    count = params.shape[0]
    h = control_step / substeps
    total_drawn = 0.0
    for index in range(count):
        p = params[index]
        s = state[index]
        out = outputs[index]
        target, lagging, supply_pressure, connections = begin_control_step(
            p, s, out, commands[index], supply
        )
        spacer = p[P_SPACER] == 1.0
        for _ in range(substeps):
            connections = substep_connections(
                p, s, target, lagging, supply_pressure, connections, h
            )
            total_drawn += heun_pneumatics(p, s, s[S_POSITION], s[S_VELOCITY], h, connections, out)
            if not spacer:
                rig_mechanics_substep(p, s, h, out)
        finish_outputs(p, s, s[S_POSITION], control_step, out)
        if spacer:
            s[S_POSITION] = p[P_STROKE]
            s[S_VELOCITY] = 0.0
            out[O_FRICTION_FORCE] = 0.0
            out[O_END_STOP_FORCE] = -(out[O_PNEUMATIC_FORCE] + p[P_GRAVITY_FORCE])
    draw_from_tank(supply, total_drawn)


@compiled
def rig_rates(p, y, command, supply_pressure):
    """Right-hand side of the rig ODE for the adaptive reference solver.

    State y follows the S_* layout (9 entries). Uses the same physics functions as the
    fixed-step kernels. The spool lag (if any) is a state; without it the spool follows
    the command instantly.
    """
    rates = np.zeros(y.shape[0])
    target = centered_voltage(command, p[P_OFFSET], p[P_UMIN], p[P_UMAX])
    spool = target
    if p[P_SPOOL_TAU] > 0.0:
        spool = y[S_SPOOL]
        rates[S_SPOOL] = (target - spool) / p[P_SPOOL_TAU]
    cap_source, cap_conductance, rod_source, rod_conductance = valve_connections(
        p, spool, supply_pressure
    )
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    spacer = p[P_SPACER] == 1.0
    if spacer:
        v = 0.0
    dpc, dpr, fc, fr, draw = pneumatic_rates(
        p,
        y[S_CAP_PRESSURE],
        y[S_ROD_PRESSURE],
        max(y[S_CAP_MASS], 1e-12),
        max(y[S_ROD_MASS], 1e-12),
        x,
        v,
        cap_source,
        cap_conductance,
        rod_source,
        rod_conductance,
    )
    rates[S_CAP_PRESSURE] = dpc
    rates[S_ROD_PRESSURE] = dpr
    rates[S_CAP_MASS] = fc
    rates[S_ROD_MASS] = fr
    rates[S_AIR_CONSUMED] = draw
    if spacer:
        return rates
    model = int(p[P_FRICTION_MODEL])
    if model == FRICTION_LUGRE:
        g = stribeck_curve(v, p[P_FS], p[P_FC], p[P_VS], p[P_EXPONENT])
        rates[S_BRISTLE] = v - p[P_SIGMA0] * abs(v) * y[S_BRISTLE] / g
    force = (
        piston_force(
            y[S_CAP_PRESSURE],
            y[S_ROD_PRESSURE],
            p[P_PATM],
            p[P_CAP_AREA],
            p[P_ROD_AREA],
            p[P_ROD_SECTION],
        )
        + p[P_GRAVITY_FORCE]
    )
    stop = end_stop_force(x, v, p[P_STROKE], p[P_STOP_STIFFNESS], p[P_STOP_DAMPING])
    friction = friction_of(p, v, y[S_BRISTLE])
    rates[S_POSITION] = v
    rates[S_VELOCITY] = (force + stop - friction) / p[P_MOVING_MASS]
    return rates
