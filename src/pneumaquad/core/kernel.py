"""Compiled kernels: the pneumatic state of N actuators advanced by one control step.

Two entry points share every physics function of :mod:`pneumaquad.core.physics`:

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

import numpy as np

from pneumaquad.core.jit import compiled
from pneumaquad.core.layout import (
    O_END_STOP_FORCE,
    O_FRICTION_FORCE,
    O_PNEUMATIC_FORCE,
    P_CAP_AREA,
    P_CV,
    P_EXPONENT,
    P_FC,
    P_FRICTION_MODEL,
    P_FS,
    P_GRAVITY_FORCE,
    P_MOVING_MASS,
    P_OFFSET,
    P_PATM,
    P_ROD_AREA,
    P_ROD_SECTION,
    P_SIGMA0,
    P_SPACER,
    P_SPOOL_TAU,
    P_STOP_DAMPING,
    P_STOP_STIFFNESS,
    P_STROKE,
    P_UMAX,
    P_UMIN,
    P_VS,
    S_AIR_CONSUMED,
    S_BRISTLE,
    S_CAP_MASS,
    S_CAP_PRESSURE,
    S_POSITION,
    S_ROD_MASS,
    S_ROD_PRESSURE,
    S_SPOOL,
    S_VELOCITY,
)
from pneumaquad.core.physics.force import end_stop_force, piston_force
from pneumaquad.core.physics.friction import (
    FRICTION_COULOMB,
    FRICTION_COULOMB_VISCOUS,
    FRICTION_LUGRE,
    stribeck_curve,
)
from pneumaquad.core.physics.valve import (
    centered_voltage,
)
from pneumaquad.core.pneumatics import (
    advance_bristle,
    begin_control_step,
    draw_from_tank,
    finish_outputs,
    friction_of,
    friction_slope_of,
    heun_pneumatics,
    pneumatic_rates,
    substep_connections,
    valve_connections,
)


@compiled
def step_actuators(
    params, state, commands, positions, velocities, control_step, substeps, supply, outputs
):
    """Advance N externally driven actuators by one control step.

    Parameters
    ----------
    params : ndarray (N, N_PARAMETERS)
        Packed parameters (:func:`pneumaquad.core.actuator.pack_parameters`).
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
    damping = friction_slope_of(p, v, s[S_BRISTLE])
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
