"""Compiled control step of the robot: actuator sampling, controllers, forces to MuJoCo.

The coupling is sampled at the instant the cylinder forces act. Each control step runs
between MuJoCo's two step halves (``mj_step1``: kinematics at the present joint angles;
``mj_step2``: forces, accelerations, integration), in two parts, for all cylinders at once:

1. :func:`sample_actuators` reads every piston position and velocity from the present
   tendon lengths and velocities and brings the chambers to the present instant: the
   pneumatic kernel (:func:`pneumaquad.kernel.step_actuators`) integrates the last
   interval along the straight piston path from the previous sample to the present one,
   so the chamber volumes it integrates end exactly at the volumes MuJoCo's motion gives
   (a closed chamber keeps P·V^n). The pneumatic force is that of the present state.
2. :func:`control_actuators` turns joint-angle references into piston references through
   the linkage (eq 5.2.1-5.2.6), runs the PID controllers (valve voltage out, held until
   the next sample) and writes the cylinder forces into ``data.ctrl`` and the seal
   friction into the tendons.

The force over a step is the one of the state at the step's start and the piston motion
over the step is MuJoCo's own (a symplectic-Euler exchange): a lossless air spring keeps
its energy. Sampling the pistons after ``mj_step`` instead reads tendon lengths computed
before the last integration, one step old, which feeds energy into the legs.
No Python loop over actuators.
"""

from __future__ import annotations

import math

import numpy as np

from pneumaquad.control.pid import (
    C_INTEGRAL,
    G_KD,
    G_KI,
    G_KP,
    G_UMAX,
    G_UMIN,
    N_GAINS,
    pid_update,
)
from pneumaquad.jit import compiled
from pneumaquad.kernel import step_actuators
from pneumaquad.layout import (
    O_PNEUMATIC_FORCE,
    P_OFFSET,
    P_STROKE,
    S_BRISTLE,
    S_CAP_MASS,
    S_CAP_PRESSURE,
    S_POSITION,
    S_ROD_MASS,
    S_ROD_PRESSURE,
    S_VELOCITY,
)
from pneumaquad.physics.friction import stribeck_curve
from pneumaquad.pneumatics import friction_of, friction_slope_of, state_outputs

# Per-joint linkage rows: l1, l3, γ0, l2, direction (see pneumaquad.robot.linkage).
L_CHILD = 0
L_PARENT = 1
L_GAMMA_ZERO = 2
L_RETRACTED = 3
L_DIRECTION = 4
N_LINKAGE = 5

# Per-joint seal friction rows for MuJoCo's dry friction: Fs, Fc, vS, i, viscous.
F_STATIC = 0
F_COULOMB = 1
F_STRIBECK_VELOCITY = 2
F_EXPONENT = 3
F_VISCOUS = 4
N_SEAL = 5

# Per-joint extra controller settings.
X_FORCE_GAIN = 0  # force feedback gain [V/N]
X_FORCE_TAU = 1  # low-pass time constant of the force mean [s]
X_COMMANDED = 2  # 1: closed loop, 0: valve held at its offset, 2: open loop voltage
X_FORCE_TRACKING = 3  # force tracking gain [V/N]; > 0: force_reference is a set-point
X_FORCE_STIFFNESS = 4  # factor on Kp and Kd while tracking forces (the stance's spring)
N_EXTRA = 5

MODE_UNCOMMANDED = 0.0
MODE_CLOSED_LOOP = 1.0
MODE_OPEN_LOOP = 2.0

# Coupling flags (one small int array per simulation).
K_PENDING = 0  # 1: the chambers are one interval behind the present kinematics
K_FRESH = 1  # 1: MuJoCo's position and velocity stages ran for the present state
N_COUPLING = 2


@compiled
def piston_from_angle(linkage_row, angle: float) -> float:
    """Piston extension x [m] for joint angle θ [rad] (eq 5.2.1, 5.2.3, 5.2.5)."""
    l1 = linkage_row[L_CHILD]
    l3 = linkage_row[L_PARENT]
    gamma = linkage_row[L_GAMMA_ZERO] + linkage_row[L_DIRECTION] * angle
    return math.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * math.cos(gamma)) - linkage_row[L_RETRACTED]


@compiled
def set_seal_friction(seal, tendon_ids, tendon_velocity, tendon_frictionloss, tendon_damping,
                      index: int) -> None:
    """Seal friction of cylinder ``index`` as the tendon's dry friction in MuJoCo: the
    Stribeck breakaway force at the current piston speed (eq 4.2.6) as ``frictionloss``
    [N], the viscous coefficient as ``damping`` [N s/m]."""
    tendon = tendon_ids[index]
    row = seal[index]
    tendon_frictionloss[tendon] = stribeck_curve(
        tendon_velocity[tendon], row[F_STATIC], row[F_COULOMB], row[F_STRIBECK_VELOCITY],
        row[F_EXPONENT],
    )
    tendon_damping[tendon] = row[F_VISCOUS]


@compiled
def sample_actuators(
    tendon_length,
    tendon_velocity,
    tendon_ids,
    linkage,
    params,
    state,
    supply,
    outputs,
    commands,
    positions,
    velocities,
    coupling,
    control_step: float,
    substeps: int,
) -> int:
    """Read the pistons from the present kinematics and bring the chambers up to date.

    ``positions`` [m] (clipped to the stroke) and ``velocities`` [m/s] are filled from
    the tendons. Where ``coupling[K_PENDING]`` is set, the chambers advance over the last
    ``control_step`` [s] with the valve ``commands`` [V] held, the piston moving linearly
    from its previous sample (``state[:, S_POSITION]``) to the present one; else only the
    force and temperatures of the present state are filled. ``outputs`` then holds the
    pneumatic force and chamber temperatures of the present instant and the mean flows
    of the last interval.

    Returns
    -------
    int
        -1 when every actuator state is finite, else the index of the first cylinder
        whose piston or chambers are not.
    """
    count = params.shape[0]
    for i in range(count):
        tendon = tendon_ids[i]
        x = tendon_length[tendon] - linkage[i, L_RETRACTED]
        positions[i] = min(max(x, 0.0), params[i, P_STROKE])
        velocities[i] = tendon_velocity[tendon]
    if coupling[K_PENDING] != 0:
        for i in range(count):
            state[i, S_VELOCITY] = (positions[i] - state[i, S_POSITION]) / control_step
        step_actuators(params, state, commands, state[:, S_POSITION], state[:, S_VELOCITY],
                       control_step, substeps, supply, outputs)
        coupling[K_PENDING] = 0
    else:
        for i in range(count):
            state_outputs(params[i], state[i], positions[i], outputs[i])
    bad = -1
    for i in range(count):
        state[i, S_POSITION] = positions[i]
        s = state[i]
        if bad < 0 and not (
            math.isfinite(positions[i]) and math.isfinite(velocities[i])
            and math.isfinite(s[S_CAP_PRESSURE]) and math.isfinite(s[S_ROD_PRESSURE])
            and math.isfinite(s[S_CAP_MASS]) and math.isfinite(s[S_ROD_MASS])
        ):
            bad = i
    return bad


@compiled
def control_actuators(
    tendon_velocity,
    tendon_ids,
    actuator_ids,
    control,
    tendon_frictionloss,
    tendon_damping,
    linkage,
    seal,
    mujoco_friction: bool,
    params,
    state,
    outputs,
    gains,
    gain_scale,
    extra,
    pid_state,
    force_reference,
    reference_angles,
    open_loop_voltage,
    commands,
    positions,
    velocities,
    reference_positions,
    control_step: float,
) -> None:
    """Controllers and cylinder forces for the interval that starts now.

    Arrays are per cylinder (index i) unless noted; MuJoCo arrays are indexed through
    ``tendon_ids`` / ``actuator_ids``. Reads the present ``positions``, ``velocities``
    and ``outputs`` of :func:`sample_actuators`; fills ``commands`` [V] (held until the
    next sample) and ``reference_positions`` [m]. ``gain_scale`` multiplies the PID gains
    (the gain-scheduling hook writes it). With ``mujoco_friction`` the seal friction
    becomes the tendon's dry friction (the Stribeck breakaway at the present speed, used
    from MuJoCo's next constraint build on) and viscous damping; otherwise the actuator
    file's force law is applied through the motor, its slope as tendon damping so
    MuJoCo's implicit integrator treats it stably (the damping force MuJoCo already
    computed for this step with the previous slope is added back to the motor force, so
    the explicit force is exactly the friction law's).

    ``force_reference`` [N] is per cylinder either the low-pass mean of its pneumatic
    force (pressure feedback: ``voltage -= X_FORCE_GAIN · (F − mean)``, a damping term)
    or, where ``extra[i, X_FORCE_TRACKING]`` = k_F > 0, a force set-point written by the
    caller: ``voltage += k_F · (F_set − F)``, with the PID's integral off and its Kp and
    Kd multiplied by ``extra[i, X_FORCE_STIFFNESS]`` = s, so that the cylinder pushes
    with F_set plus a position spring of stiffness s·Kp / k_F [N/m] and a damper of
    s·Kd / k_F [N s/m] (a compliant, force-controlled stance; the integral would
    otherwise pull the piston back to its reference whatever the load).
    """
    count = params.shape[0]
    scaled = np.empty(N_GAINS)
    for i in range(count):
        stroke = params[i, P_STROKE]
        mode = extra[i, X_COMMANDED]
        if mode == MODE_CLOSED_LOOP:
            target = piston_from_angle(linkage[i], reference_angles[i])
            reference_positions[i] = min(max(target, 0.0), stroke)
            for k in range(N_GAINS):
                scaled[k] = gains[i, k]
            scaled[G_KP] *= gain_scale[i]
            scaled[G_KI] *= gain_scale[i]
            scaled[G_KD] *= gain_scale[i]
            tracking = extra[i, X_FORCE_TRACKING]
            if tracking > 0.0:
                scaled[G_KP] *= extra[i, X_FORCE_STIFFNESS]
                scaled[G_KD] *= extra[i, X_FORCE_STIFFNESS]
                scaled[G_KI] = 0.0
            if scaled[G_KI] == 0.0:
                pid_state[i, C_INTEGRAL] = 0.0
            voltage = pid_update(
                scaled, pid_state[i], reference_positions[i], positions[i], control_step
            )
            # one force term for both uses of force_reference: the set-point (tracking)
            # or the low-pass mean (pressure feedback)
            force_gain = tracking if tracking > 0.0 else extra[i, X_FORCE_GAIN]
            if force_gain > 0.0:
                voltage += force_gain * (force_reference[i] - outputs[i, O_PNEUMATIC_FORCE])
                voltage = min(max(voltage, scaled[G_UMIN]), scaled[G_UMAX])
            commands[i] = voltage
        elif mode == MODE_OPEN_LOOP:
            reference_positions[i] = positions[i]
            commands[i] = open_loop_voltage[i]
        else:
            reference_positions[i] = positions[i]
            commands[i] = params[i, P_OFFSET]
    for i in range(count):
        tendon = tendon_ids[i]
        force = outputs[i, O_PNEUMATIC_FORCE]
        tau = extra[i, X_FORCE_TAU]
        if extra[i, X_FORCE_TRACKING] == 0.0:
            force_reference[i] += control_step / (tau + control_step) * (force - force_reference[i])
        v = velocities[i]
        if mujoco_friction:
            set_seal_friction(seal, tendon_ids, tendon_velocity, tendon_frictionloss,
                              tendon_damping, i)
        else:
            applied_damping = tendon_damping[tendon]  # in MuJoCo's passive force already
            force += applied_damping * v - friction_of(params[i], v, state[i, S_BRISTLE])
            tendon_damping[tendon] = max(friction_slope_of(params[i], v, state[i, S_BRISTLE]),
                                         0.0)
        control[actuator_ids[i]] = force


@compiled
def robot_control_step(
    tendon_length,
    tendon_velocity,
    tendon_ids,
    actuator_ids,
    control,
    tendon_frictionloss,
    tendon_damping,
    linkage,
    seal,
    mujoco_friction: bool,
    params,
    state,
    supply,
    outputs,
    gains,
    gain_scale,
    extra,
    pid_state,
    force_reference,
    reference_angles,
    open_loop_voltage,
    commands,
    positions,
    velocities,
    reference_positions,
    coupling,
    control_step: float,
    substeps: int,
) -> int:
    """One control step at the present kinematics: :func:`sample_actuators`, then
    :func:`control_actuators`; marks the chambers as owing the interval that follows.

    Returns the index of a cylinder whose state went non-finite, else -1 (see
    :func:`sample_actuators`).
    """
    bad = sample_actuators(
        tendon_length, tendon_velocity, tendon_ids, linkage, params, state, supply, outputs,
        commands, positions, velocities, coupling, control_step, substeps,
    )
    control_actuators(
        tendon_velocity, tendon_ids, actuator_ids, control, tendon_frictionloss,
        tendon_damping, linkage, seal, mujoco_friction, params, state, outputs, gains,
        gain_scale, extra, pid_state, force_reference, reference_angles, open_loop_voltage,
        commands, positions, velocities, reference_positions, control_step,
    )
    coupling[K_PENDING] = 1
    return bad
