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

Actuators are arrays of named records (:mod:`pneumaquad.core.layout`); each loop takes
an actuator's records once (``p = params[i]``) and hands them to the per-actuator
functions of :mod:`pneumaquad.core.pneumatics`. The loops run substep by substep over all
actuators (not actuator by actuator over all substeps), two actuators at a time, the
first stage of Heun's method of both before the rest of either: one actuator's substep
is a long chain of dependent divisions, square roots and powers, and the other's, which
does not depend on it, fills the processor's idle units meanwhile. The arithmetic of each
actuator is the same as one at a time, so are the results, bit for bit. What each
actuator sets up at the step's start waits between its substeps in a work record
(:data:`pneumaquad.core.layout.STEP_WORK_DTYPE`).
"""

import numpy as np

from pneumaquad.core.jit import compiled
from pneumaquad.core.layout import STEP_WORK_DTYPE
from pneumaquad.core.physics.force import end_stop_force
from pneumaquad.core.physics.friction import (
    FRICTION_COULOMB,
    FRICTION_COULOMB_VISCOUS,
    FRICTION_LUGRE,
    stribeck_curve,
)
from pneumaquad.core.physics.valve import centered_voltage
from pneumaquad.core.pneumatics import (
    advance_bristle,
    begin_control_step,
    draw_from_tank,
    finish_outputs,
    flow_constants,
    friction_and_slope_of,
    friction_of,
    heun_finish,
    heun_first_rates,
    heun_pneumatics,
    pneumatic_force_of,
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
    params : ndarray (N,) of ACTUATOR_PARAMETERS_DTYPE
        Packed parameters (:func:`pneumaquad.core.actuator.pack_parameters`).
    state : ndarray (N,) of ACTUATOR_STATE_DTYPE
        Chamber states, updated in place. The fields ``position`` and ``velocity`` are
        overwritten with the inputs advanced over the step.
    commands : ndarray (N,)
        Valve voltages held over the step [V].
    positions, velocities : ndarray (N,)
        Piston extension [m] and velocity [m/s] at the start of the step; the position is
        moved linearly over the step.
    control_step : float
        Step length [s].
    substeps : int
        Heun substeps per control step.
    supply : ndarray (1,) of SUPPLY_DTYPE
        Shared supply state (ideal or tank), updated in place once per step.
    outputs : ndarray (N,) of ACTUATOR_OUTPUT_DTYPE
        Filled with mean flows, end-of-step forces (pneumatic and friction, the latter at
        the given velocity) and temperatures.
    """
    if params.shape[0] == 1:  # nothing to interleave: its set-up stays in registers
        drawn = advance_one_actuator(params[0], state[0], outputs[0], commands[0],
                                     positions[0], velocities[0], supply[0], control_step,
                                     substeps, True)
        draw_from_tank(supply[0], drawn)
        return
    advance_actuators(params, state, commands, positions, velocities, control_step, substeps,
                      supply, outputs, True)


@compiled(inline=True)
def advance_actuators(
    params, state, commands, positions, velocities, control_step, substeps, supply, outputs,
    friction_output,
):
    """:func:`step_actuators`, with the friction force output optional.

    With ``friction_output`` False, ``outputs.friction_force`` is left at zero and the
    friction law (a Stribeck curve and a tanh per actuator) is not evaluated: the robot's
    coupling reads its seal friction from MuJoCo's solver or evaluates the law itself at
    the present velocity, so it never reads this output.

    ``positions`` and ``velocities`` may be the state's own fields (the coupling passes
    them): each actuator's velocity is read at every substep and its position only at the
    step's start.
    """
    count = params.shape[0]
    h = control_step / substeps
    # allocated here, not kept in the bank: numba types an array of records slowly when a
    # Python call hands it over (about 18 us for this one per chunk of a walk), and the
    # allocation costs tens of nanoseconds
    work = np.empty(count, STEP_WORK_DTYPE)
    begin_step(params, state, commands, supply, outputs, work)
    for index in range(count):
        state[index].position = positions[index]
    for _ in range(substeps):
        for index in range(0, count, 2):  # two at a time: their chains interleave
            paired = index + 1 < count
            s = state[index]
            velocity = velocities[index]
            started = substep_begin(params[index], s, work[index], s.position, velocity, h)
            if paired:
                other = state[index + 1]
                other_velocity = velocities[index + 1]
                other_started = substep_begin(params[index + 1], other, work[index + 1],
                                              other.position, other_velocity, h)
            substep_end(params[index], s, work[index], s.position, velocity, h,
                        outputs[index], started)
            s.position += h * velocity
            if paired:
                substep_end(params[index + 1], other, work[index + 1], other.position,
                            other_velocity, h, outputs[index + 1], other_started)
                other.position += h * other_velocity
    for index in range(count):
        finish_actuator(params[index], state[index], outputs[index], velocities[index],
                        control_step, friction_output)
    finish_step(work, supply)


@compiled(inline=True)
def advance_one_actuator(p, s, out, command, position, velocity, supply_record,
                         control_step, substeps, friction_output):
    """:func:`advance_actuators` of one actuator, substep after substep; returns the mass
    drawn from the supply [kg] (not yet drawn from ``supply_record``)."""
    h = control_step / substeps
    target, lagging, supply_pressure, connections = begin_control_step(
        p, s, out, command, supply_record
    )
    constants = flow_constants(p)
    drawn = 0.0
    s.position = position
    for _ in range(substeps):
        connections = substep_connections(
            p, s, target, lagging, supply_pressure, connections, h
        )
        drawn += heun_pneumatics(p, constants, s, s.position, velocity, h, connections, out)
        s.position += h * velocity
    finish_actuator(p, s, out, velocity, control_step, friction_output)
    return drawn


@compiled(inline=True)
def finish_actuator(p, s, out, velocity, control_step, friction_output):
    """An externally driven actuator's bristle, velocity and outputs at the step's end."""
    s.bristle_deflection = advance_bristle(p, s.bristle_deflection, velocity, control_step)
    s.velocity = velocity
    finish_outputs(p, s, s.position, control_step, out)
    if friction_output:
        out.friction_force = friction_of(p, velocity, s.bristle_deflection)


@compiled(inline=True)
def begin_step(params, state, commands, supply, outputs, work):
    """Set up N actuators' control step (:func:`pneumaquad.core.pneumatics.begin_control_step`).

    ``supply`` holds one record that all share, or one per actuator. Fills the step's
    work records ``work`` (:data:`pneumaquad.core.layout.STEP_WORK_DTYPE`), one per
    actuator: its target voltage, supply pressure and valve connections, and the mass
    drawn so far (zero).
    """
    count = params.shape[0]
    shared = supply.shape[0] == 1
    for index in range(count):
        p = params[index]
        w = work[index]
        target, _, supply_pressure, connections = begin_control_step(
            p, state[index], outputs[index], commands[index], supply[0 if shared else index]
        )
        w.target_voltage = target
        w.supply_pressure = supply_pressure
        keep_connections(w, connections)
        w.drawn_mass = 0.0


@compiled(inline=True)
def keep_connections(w, connections):
    """Store valve connections (:func:`pneumaquad.core.pneumatics.valve_connections`) in
    a work record."""
    w.cap_source_pressure = connections[0]
    w.cap_conductance = connections[1]
    w.rod_source_pressure = connections[2]
    w.rod_conductance = connections[3]


@compiled(inline=True)
def substep_begin(p, s, w, position, velocity, time_step):
    """The first half of an actuator's Heun substep (:func:`heun_pneumatics`) from its
    work record ``w``: the spool moved if it lags, and the rates at the substep's start.
    Returns what :func:`substep_end` takes: (connections, flow constants, rates)."""
    connections = (
        w.cap_source_pressure, w.cap_conductance, w.rod_source_pressure, w.rod_conductance
    )
    if p.spool_time_constant > 0.0:
        connections = substep_connections(
            p, s, w.target_voltage, True, w.supply_pressure, connections, time_step
        )
        keep_connections(w, connections)
    constants = flow_constants(p)
    return connections, constants, heun_first_rates(
        p, constants, s, position, velocity, connections
    )


@compiled(inline=True)
def substep_end(p, s, w, position, velocity, time_step, out, started):
    """The second half of the substep begun by :func:`substep_begin` (``started``); adds
    the drawn mass to ``w``."""
    connections, constants, first = started
    w.drawn_mass += heun_finish(
        p, constants, s, position, velocity, time_step, connections, out, first
    )


@compiled(inline=True)
def finish_step(work, supply):
    """Draw the step's air from the supply: the sum over all actuators (in their order)
    from a shared record, or each actuator's from its own."""
    if supply.shape[0] == 1:
        total = 0.0
        for index in range(work.shape[0]):
            total += work[index].drawn_mass
        draw_from_tank(supply[0], total)
    else:
        for index in range(work.shape[0]):
            draw_from_tank(supply[index], work[index].drawn_mass)


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
    x = s.position
    v = s.velocity
    mass = p.moving_mass
    force = pneumatic_force_of(p, s) + p.gravity_force
    stop = end_stop_force(x, v, p.stroke, p.end_stop_stiffness, p.end_stop_damping)
    model = p.friction_model
    dry_model = model in (FRICTION_COULOMB, FRICTION_COULOMB_VISCOUS)
    resting_on_stop = dry_model and v == 0.0 and stop != 0.0
    if resting_on_stop:
        # A piston stuck on a stop: the rigid stop reacts only as much as the load presses
        # into it, and stores nothing, so when the load pulls away the contact spring's
        # penetration is dropped and friction alone holds the piston (breakaway at Fs).
        stop = max(0.0, -force) if stop > 0.0 else min(0.0, -force)
        if stop == 0.0:
            x = min(max(x, 0.0), p.stroke)
    stiffness = 0.0
    stop_damping = 0.0
    if stop != 0.0 and not resting_on_stop:
        stiffness = p.end_stop_stiffness
        stop_damping = p.end_stop_damping
    # the law at the start velocity; a LuGre force is taken again after the bristle step
    friction, damping = friction_and_slope_of(p, v, s.bristle_deflection)
    effective_mass = mass + h * (damping + stop_damping) + h * h * stiffness
    if dry_model:
        viscous = p.viscous_coefficient if model == FRICTION_COULOMB_VISCOUS else 0.0
        free = v + h * (force + stop - viscous * v - h * stiffness * v) / effective_mass
        needed = effective_mass * free / h
        breakaway = (
            p.static_force if (v == 0.0 and model == FRICTION_COULOMB_VISCOUS)
            else p.coulomb_force
        )
        if abs(needed) <= breakaway:
            v_new = 0.0
            dry = needed
        else:
            dry = p.coulomb_force if free > 0.0 else -p.coulomb_force
            v_new = free - h * dry / effective_mass
        friction = dry + viscous * v_new
    else:
        if model == FRICTION_LUGRE:
            s.bristle_deflection = advance_bristle(p, s.bristle_deflection, v, h)
            friction = friction_of(p, v, s.bristle_deflection)
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
    s.velocity = v_new
    s.position = x + h * v_new
    out.friction_force = friction
    out.end_stop_force = stop


@compiled
def step_rigs(params, state, commands, control_step, substeps, supply, outputs):
    """Advance N single-DoF rigs (cylinder + load) by one control step.

    Parameters as in :func:`step_actuators`, without external positions: each rig's
    ``position`` and ``velocity`` are its own states; ``supply`` holds one record that all
    rigs share or one per rig. Per substep the chamber states take a Heun step with the
    piston moving at its current velocity, then the piston takes a linearly implicit step
    with the new pressures (:func:`rig_mechanics_substep`). In spacer mode the piston
    stays at full extension and the end-stop force is the load the spacer carries.
    """
    advance_rigs(params, state, commands, control_step, substeps, supply, outputs,
                 np.empty(params.shape[0], STEP_WORK_DTYPE))


@compiled(inline=True)
def advance_rigs(params, state, commands, control_step, substeps, supply, outputs, work):
    """:func:`step_rigs` in the work records ``work`` ((N,) of
    :data:`pneumaquad.core.layout.STEP_WORK_DTYPE`, overwritten: a loop over control steps
    allocates it once)."""
    count = params.shape[0]
    if count == 1:  # nothing to interleave: its set-up stays in registers
        drawn = advance_one_rig(params[0], state[0], outputs[0], commands[0], supply[0],
                                control_step, substeps)
        draw_from_tank(supply[0], drawn)
        return
    h = control_step / substeps
    begin_step(params, state, commands, supply, outputs, work)
    for _ in range(substeps):
        for index in range(0, count, 2):  # two at a time, as in advance_actuators
            paired = index + 1 < count
            p = params[index]
            s = state[index]
            started = substep_begin(p, s, work[index], s.position, s.velocity, h)
            if paired:
                q = params[index + 1]
                other = state[index + 1]
                other_started = substep_begin(q, other, work[index + 1], other.position,
                                              other.velocity, h)
            substep_end(p, s, work[index], s.position, s.velocity, h, outputs[index],
                        started)
            if paired:
                substep_end(q, other, work[index + 1], other.position, other.velocity, h,
                            outputs[index + 1], other_started)
            if p.spacer == 0:
                rig_mechanics_substep(p, s, h, outputs[index])
            if paired and q.spacer == 0:
                rig_mechanics_substep(q, other, h, outputs[index + 1])
    for index in range(count):
        finish_rig(params[index], state[index], outputs[index], control_step)
    finish_step(work, supply)


@compiled(inline=True)
def advance_one_rig(p, s, out, command, supply_record, control_step, substeps):
    """:func:`advance_rigs` of one rig, substep after substep; returns the mass drawn from
    the supply [kg] (not yet drawn from ``supply_record``)."""
    h = control_step / substeps
    target, lagging, supply_pressure, connections = begin_control_step(
        p, s, out, command, supply_record
    )
    constants = flow_constants(p)
    spacer = p.spacer != 0
    drawn = 0.0
    for _ in range(substeps):
        connections = substep_connections(
            p, s, target, lagging, supply_pressure, connections, h
        )
        drawn += heun_pneumatics(p, constants, s, s.position, s.velocity, h, connections, out)
        if not spacer:
            rig_mechanics_substep(p, s, h, out)
    finish_rig(p, s, out, control_step)
    return drawn


@compiled(inline=True)
def finish_rig(p, s, out, control_step):
    """A rig's outputs at the step's end; in spacer mode the piston held at full extension
    and the end-stop force the load the spacer carries."""
    finish_outputs(p, s, s.position, control_step, out)
    if p.spacer != 0:
        s.position = p.stroke
        s.velocity = 0.0
        out.friction_force = 0.0
        out.end_stop_force = -(out.pneumatic_force + p.gravity_force)


@compiled
def rig_rates(params, state, command, supply_pressure, rates):
    """Right-hand side of the rig ODE for the adaptive reference solver.

    ``params``, ``state`` and ``rates`` are arrays of one record: the rig's parameters
    (ACTUATOR_PARAMETERS_DTYPE), its state and, filled here, the time derivative of each
    state field (both ACTUATOR_STATE_DTYPE: [Pa/s], [kg/s], [V/s], [m/s], [m/s^2]) at a
    valve command [V] and supply pressure [Pa]. (Arrays rather than records, because
    the solver calls this from Python many times per control step and numba dispatches
    arrays of records faster than single records.) Uses the same physics functions as
    the fixed-step kernels. The spool lag (if any) is a state; without it the spool
    follows the command instantly.
    """
    p = params[0]
    y = state[0]
    r = rates[0]
    target = centered_voltage(command, p.offset_voltage, p.min_voltage, p.max_voltage)
    spool = target
    r.spool_voltage = 0.0
    if p.spool_time_constant > 0.0:
        spool = y.spool_voltage
        r.spool_voltage = (target - spool) / p.spool_time_constant
    cap_source, cap_conductance, rod_source, rod_conductance = valve_connections(
        p, spool, supply_pressure
    )
    x = y.position
    v = y.velocity
    spacer = p.spacer != 0
    if spacer:
        v = 0.0
    dpc, dpr, fc, fr, draw = pneumatic_rates(
        p,
        flow_constants(p),
        y.cap_pressure,
        y.rod_pressure,
        max(y.cap_mass, 1e-12),
        max(y.rod_mass, 1e-12),
        x,
        v,
        cap_source,
        cap_conductance,
        rod_source,
        rod_conductance,
    )
    r.cap_pressure = dpc
    r.rod_pressure = dpr
    r.cap_mass = fc
    r.rod_mass = fr
    r.air_consumed = draw
    r.bristle_deflection = 0.0
    r.position = 0.0
    r.velocity = 0.0
    if spacer:
        return
    if p.friction_model == FRICTION_LUGRE:
        g = stribeck_curve(
            v, p.static_force, p.coulomb_force, p.stribeck_velocity, p.stribeck_exponent
        )
        r.bristle_deflection = v - p.bristle_stiffness * abs(v) * y.bristle_deflection / g
    force = pneumatic_force_of(p, y) + p.gravity_force
    stop = end_stop_force(x, v, p.stroke, p.end_stop_stiffness, p.end_stop_damping)
    friction = friction_of(p, v, y.bristle_deflection)
    r.position = v
    r.velocity = (force + stop - friction) / p.moving_mass
