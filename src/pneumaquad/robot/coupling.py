"""Compiled control step of the robot: controllers, pneumatic kernel, forces to MuJoCo.

One call per control step does, for all cylinders at once: read piston positions and
velocities from MuJoCo's tendon lengths and velocities, turn joint-angle references into
piston references through the linkage (eq 5.2.1-5.2.6), run the PID controllers (valve
voltage out), advance every actuator with :func:`pneumaquad.kernel.step_actuators`, and
write the cylinder forces into ``data.ctrl`` and the seal friction into the model.
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
    O_FRICTION_FORCE,
    O_PNEUMATIC_FORCE,
    P_OFFSET,
    P_STROKE,
    S_BRISTLE,
)
from pneumaquad.physics.friction import stribeck_curve
from pneumaquad.pneumatics import friction_slope_of

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
    control_step: float,
    substeps: int,
):
    """Advance controllers and actuators by one control step and set MuJoCo's inputs.

    Arrays are per cylinder (index i) unless noted; MuJoCo arrays are indexed through
    ``tendon_ids`` / ``actuator_ids``. ``commands``, ``positions``, ``velocities`` and
    ``reference_positions`` are filled for recording. ``gain_scale`` multiplies the PID
    gains (the gain-scheduling hook writes it). With ``mujoco_friction`` the seal
    friction becomes the tendon's dry friction (Stribeck breakaway at the current speed)
    and viscous damping; otherwise the actuator file's force law is applied through the
    motor, its slope as tendon damping so MuJoCo's implicit integrator treats it stably.

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
        tendon = tendon_ids[i]
        stroke = params[i, P_STROKE]
        x = tendon_length[tendon] - linkage[i, L_RETRACTED]
        positions[i] = min(max(x, 0.0), stroke)
        velocities[i] = tendon_velocity[tendon]
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
    step_actuators(
        params, state, commands, positions, velocities, control_step, substeps, supply, outputs
    )
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
            slope = max(friction_slope_of(params[i], v, state[i, S_BRISTLE]), 0.0)
            tendon_damping[tendon] = slope
            force += slope * v - outputs[i, O_FRICTION_FORCE]
        control[actuator_ids[i]] = force
