"""Compiled control step of the robot: actuator sampling, controllers, forces to MuJoCo.

The coupling is sampled at the instant the cylinder forces act. Each control step runs
between MuJoCo's two step halves (``mj_step1``: kinematics at the present joint angles;
``mj_step2``: forces, accelerations, integration), in two parts, for all cylinders at once:

1. :func:`sample_actuators` reads every piston position and velocity from the present
   tendon lengths and velocities and brings the chambers to the present instant: the
   pneumatic kernel (:func:`pneumaquad.core.kernel.step_actuators`) integrates the last
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
from typing import NamedTuple

import numpy as np

from pneumaquad.core.bank import ActuatorArrays
from pneumaquad.core.control.pid import PID_GAINS_DTYPE, pid_update, scale_gains
from pneumaquad.core.jit import compiled
from pneumaquad.core.kernel import advance_actuators
from pneumaquad.core.physics.friction import stribeck_curve
from pneumaquad.core.pneumatics import friction_and_slope_of, state_outputs

#: One cylinder linkage (pneumaquad.robot.linkage, eq 5.2.1-5.2.6).
LINKAGE_DTYPE = np.dtype([
    ("child_pivot_radius", "f8"),  # l1 [m]: joint axis to the rod pin
    ("parent_pivot_radius", "f8"),  # l3 [m]: joint axis to the barrel pivot
    ("included_angle_at_zero", "f8"),  # γ0 [rad]: included angle at θ = 0
    ("retracted_length", "f8"),  # l2 [m]: pin-to-pin length at x = 0
    ("direction", "f8"),  # ±1: γ = γ0 ± θ
])

#: One cylinder's seal friction as MuJoCo dry friction (Stribeck curve eq 4.2.6 + viscous).
SEAL_DTYPE = np.dtype([
    ("static_force", "f8"),  # Fs [N]
    ("coulomb_force", "f8"),  # Fc [N]
    ("stribeck_velocity", "f8"),  # vS [m/s]
    ("stribeck_exponent", "f8"),  # i [-]
    ("viscous_coefficient", "f8"),  # [N s/m]
])

#: One joint's control settings besides the PID gains.
JOINT_CONTROL_DTYPE = np.dtype([
    ("mode", "i8"),  # MODE_UNCOMMANDED, MODE_CLOSED_LOOP or MODE_OPEN_LOOP
    ("force_feedback_gain", "f8"),  # pressure feedback about the force mean [V/N]
    ("force_feedback_time_constant", "f8"),  # low-pass of that mean [s]
    ("force_tracking_gain", "f8"),  # k_F [V/N]; > 0: force_reference is a set-point
    ("force_stiffness", "f8"),  # factor on Kp and Kd while tracking forces [-]
])

MODE_UNCOMMANDED = 0  # valve held at its offset
MODE_CLOSED_LOOP = 1  # PID on the piston position of the joint-angle reference
MODE_OPEN_LOOP = 2  # valve at open_loop_voltage

#: The coupling's bookkeeping (one record per simulation).
COUPLING_DTYPE = np.dtype([
    ("pending", "i8"),  # 1: the chambers are one interval behind the present kinematics
    ("fresh", "i8"),  # 1: MuJoCo's position and velocity stages ran for the present state
])


class MujocoBuffers(NamedTuple):
    """One simulation's MuJoCo arrays the control step reads and writes (views)."""

    tendon_length: np.ndarray  # data.ten_length [m]
    tendon_velocity: np.ndarray  # data.ten_velocity [m/s]
    control: np.ndarray  # data.ctrl: cylinder forces [N]
    tendon_frictionloss: np.ndarray  # model.tendon_frictionloss [N]
    tendon_damping: np.ndarray  # model.tendon_damping [N s/m]
    tendon_ids: np.ndarray  # tendon of each cylinder
    actuator_ids: np.ndarray  # motor of each cylinder


class Cylinders(NamedTuple):
    """Per cylinder: linkage (LINKAGE_DTYPE) and seal friction (SEAL_DTYPE)."""

    linkage: np.ndarray
    seal: np.ndarray


class Controllers(NamedTuple):
    """Per joint: PID gains and memory, settings (JOINT_CONTROL_DTYPE) and references.

    The joint-side bundle: the gains, gain scale, PID memory and open-loop voltages are
    the actuator bank's arrays (:class:`pneumaquad.core.bank.ActuatorBank`), the
    settings, force references and joint-angle references the joints' own
    (:class:`pneumaquad.robot.joints.CylinderJoints`)."""

    gains: np.ndarray  # PID_GAINS_DTYPE, pneumaquad.core.control.pid
    gain_scale: np.ndarray  # factor on Kp, Ki, Kd [-]
    settings: np.ndarray  # JOINT_CONTROL_DTYPE
    pid_state: np.ndarray  # PID_STATE_DTYPE
    force_reference: np.ndarray  # force mean or set-point [N]
    reference_angles: np.ndarray  # [rad]
    open_loop_voltage: np.ndarray  # [V]


class StepTrace(NamedTuple):
    """What the last control step used, per cylinder (for recording)."""

    commands: np.ndarray  # valve voltages held over the step [V]
    positions: np.ndarray  # piston positions [m]
    velocities: np.ndarray  # piston velocities [m/s]
    reference_positions: np.ndarray  # piston references [m]


class StepSettings(NamedTuple):
    """Scalars of the control step."""

    control_step: float  # [s]
    substeps: int  # Heun substeps of the pneumatic kernel per control step
    mujoco_friction: bool  # seal friction as MuJoCo dry friction (else the actuator's law)


@compiled
def piston_from_angle(linkage, angle: float) -> float:
    """Piston extension x [m] of a linkage record at joint angle θ [rad] (eq 5.2.1,
    5.2.3, 5.2.5)."""
    l1 = linkage.child_pivot_radius
    l3 = linkage.parent_pivot_radius
    gamma = linkage.included_angle_at_zero + linkage.direction * angle
    return math.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * math.cos(gamma)) \
        - linkage.retracted_length


@compiled
def set_seal_friction(mujoco: MujocoBuffers, seal, index: int) -> None:
    """Seal friction of cylinder ``index`` as the tendon's dry friction in MuJoCo: the
    Stribeck breakaway force at the current piston speed (eq 4.2.6) as ``frictionloss``
    [N], the viscous coefficient as ``damping`` [N s/m]."""
    tendon = mujoco.tendon_ids[index]
    row = seal[index]
    mujoco.tendon_frictionloss[tendon] = stribeck_curve(
        mujoco.tendon_velocity[tendon], row.static_force, row.coulomb_force,
        row.stribeck_velocity, row.stribeck_exponent,
    )
    mujoco.tendon_damping[tendon] = row.viscous_coefficient


@compiled(inline=True)
def sample_actuators(mujoco: MujocoBuffers, cylinders: Cylinders, actuators: ActuatorArrays,
                     trace: StepTrace, coupling, settings: StepSettings) -> int:
    """Read the pistons from the present kinematics and bring the chambers up to date.

    ``trace.positions`` [m] (clipped to the stroke) and ``trace.velocities`` [m/s] are
    filled from the tendons. Where ``coupling[0].pending`` is set, the chambers advance
    over the last control step with the valve commands held, the piston moving linearly
    from its previous sample (``state.position``) to the present one; else only
    the force and temperatures of the present state are filled. ``actuators.outputs``
    then holds the pneumatic force and chamber temperatures of the present instant and
    the mean flows of the last interval.

    Returns
    -------
    int
        -1 when every actuator state is finite, else the index of the first cylinder
        whose piston or chambers are not.
    """
    params, state, outputs = actuators.params, actuators.state, actuators.outputs
    positions, velocities = trace.positions, trace.velocities
    count = params.shape[0]
    for i in range(count):
        tendon = mujoco.tendon_ids[i]
        x = mujoco.tendon_length[tendon] - cylinders.linkage[i].retracted_length
        positions[i] = min(max(x, 0.0), params[i].stroke)
        velocities[i] = mujoco.tendon_velocity[tendon]
    dt = settings.control_step
    if coupling[0].pending != 0:
        for i in range(count):
            s = state[i]
            s.velocity = (positions[i] - s.position) / dt
        advance_actuators(params, state, trace.commands, state.position, state.velocity, dt,
                          settings.substeps, actuators.supply, outputs, False)
        coupling[0].pending = 0
    else:
        for i in range(count):
            state_outputs(params[i], state[i], positions[i], outputs[i])
    bad = -1
    for i in range(count):
        s = state[i]
        s.position = positions[i]
        if bad < 0 and not (
            math.isfinite(positions[i]) and math.isfinite(velocities[i])
            and math.isfinite(s.cap_pressure) and math.isfinite(s.rod_pressure)
            and math.isfinite(s.cap_mass) and math.isfinite(s.rod_mass)
        ):
            bad = i
    return bad


@compiled(inline=True)
def control_actuators(mujoco: MujocoBuffers, cylinders: Cylinders, actuators: ActuatorArrays,
                      controllers: Controllers, trace: StepTrace,
                      settings: StepSettings) -> None:
    """Controllers and cylinder forces for the interval that starts now.

    Reads the present ``trace.positions``, ``trace.velocities`` and ``actuators.outputs``
    of :func:`sample_actuators`; fills ``trace.commands`` [V] (held until the next sample)
    and ``trace.reference_positions`` [m]. ``controllers.gain_scale`` multiplies the PID
    gains (the gain-scheduling hook writes it). With ``settings.mujoco_friction`` the
    seal friction becomes the tendon's dry friction (the Stribeck breakaway at the
    present speed, used from MuJoCo's next constraint build on) and viscous damping;
    otherwise the actuator file's force law is applied through the motor, its slope as
    tendon damping so MuJoCo's implicit integrator treats it stably (the damping force
    MuJoCo already computed for this step with the previous slope is added back to the
    motor force, so the explicit force is exactly the friction law's).

    ``controllers.force_reference`` [N] is per cylinder either the low-pass mean of its
    pneumatic force (pressure feedback: ``voltage -= force_feedback_gain · (F − mean)``, a
    damping term) or, where ``force_tracking_gain`` = k_F > 0, a force set-point written
    by the caller: ``voltage += k_F · (F_set − F)``, with the PID's integral off and its
    Kp and Kd multiplied by ``force_stiffness`` = s, so that the cylinder pushes with
    F_set plus a position spring of stiffness s·Kp / k_F [N/m] and a damper of
    s·Kd / k_F [N s/m] (a compliant, force-controlled stance; the integral would
    otherwise pull the piston back to its reference whatever the load).
    """
    params, state, outputs = actuators.params, actuators.state, actuators.outputs
    positions, velocities = trace.positions, trace.velocities
    commands, reference_positions = trace.commands, trace.reference_positions
    control_settings = controllers.settings
    dt = settings.control_step
    count = params.shape[0]
    scaled = np.empty(1, PID_GAINS_DTYPE)[0]
    for i in range(count):
        stroke = params[i].stroke
        joint = control_settings[i]
        if joint.mode == MODE_CLOSED_LOOP:
            target = piston_from_angle(cylinders.linkage[i], controllers.reference_angles[i])
            reference_positions[i] = min(max(target, 0.0), stroke)
            scale_gains(controllers.gains[i], controllers.gain_scale[i], scaled)
            tracking = joint.force_tracking_gain
            if tracking > 0.0:
                scaled.proportional_gain *= joint.force_stiffness
                scaled.derivative_gain *= joint.force_stiffness
                scaled.integral_gain = 0.0
            if scaled.integral_gain == 0.0:
                controllers.pid_state[i].integral = 0.0
            voltage = pid_update(
                scaled, controllers.pid_state[i], reference_positions[i], positions[i], dt
            )
            # one force term for both uses of force_reference: the set-point (tracking)
            # or the low-pass mean (pressure feedback)
            force_gain = tracking if tracking > 0.0 else joint.force_feedback_gain
            if force_gain > 0.0:
                voltage += force_gain * (controllers.force_reference[i]
                                         - outputs[i].pneumatic_force)
                voltage = min(max(voltage, scaled.min_voltage), scaled.max_voltage)
            commands[i] = voltage
        elif joint.mode == MODE_OPEN_LOOP:
            reference_positions[i] = positions[i]
            commands[i] = controllers.open_loop_voltage[i]
        else:
            reference_positions[i] = positions[i]
            commands[i] = params[i].offset_voltage
    for i in range(count):
        tendon = mujoco.tendon_ids[i]
        force = outputs[i].pneumatic_force
        joint = control_settings[i]
        if joint.force_tracking_gain == 0.0:
            tau = joint.force_feedback_time_constant
            controllers.force_reference[i] += dt / (tau + dt) * (
                force - controllers.force_reference[i])
        v = velocities[i]
        if settings.mujoco_friction:
            set_seal_friction(mujoco, cylinders.seal, i)
        else:
            p = params[i]
            bristle = state[i].bristle_deflection
            applied_damping = mujoco.tendon_damping[tendon]  # in MuJoCo's passive force
            friction, slope = friction_and_slope_of(p, v, bristle)
            force += applied_damping * v - friction
            mujoco.tendon_damping[tendon] = max(slope, 0.0)
        mujoco.control[mujoco.actuator_ids[i]] = force


@compiled(inline=True)
def robot_control_step(mujoco: MujocoBuffers, cylinders: Cylinders, actuators: ActuatorArrays,
                       controllers: Controllers, trace: StepTrace, coupling,
                       settings: StepSettings) -> int:
    """One control step at the present kinematics: :func:`sample_actuators`, then
    :func:`control_actuators`; marks the chambers as owing the interval that follows.

    Returns the index of a cylinder whose state went non-finite, else -1 (see
    :func:`sample_actuators`).
    """
    bad = sample_actuators(mujoco, cylinders, actuators, trace, coupling, settings)
    control_actuators(mujoco, cylinders, actuators, controllers, trace, settings)
    coupling[0].pending = 1
    return bad
