"""A robot's cylinder-driven joints without MuJoCo: one actuator bank and the joint side.

:class:`CylinderJoints` holds the robot's cylinders in one
:class:`~pneumaquad.core.bank.ActuatorBank` (parameters, chamber state, the shared
supply, PID gains and memory, piston references, valve commands) and adds what is
particular to joints driven through a linkage: the linkage and seal-friction record of
each cylinder, the joint-control settings (mode, pressure feedback, force tracking), the
force and joint-angle references, the piston readouts and the coupling's bookkeeping;
and it bundles them for the compiled control step (:mod:`pneumaquad.robot.coupling`).
Everything comes from the robot's parameters, actuator files and linkage geometry
(:func:`pneumaquad.robot.builder.leg_linkages`); no MuJoCo data is made here, so the
coupled simulation (:class:`~pneumaquad.robot.simulation.RobotSimulation`) and the
network actuator side (:class:`~pneumaquad.network.actuator_side.ActuatorSide`) build
the same arrays in the same way.
"""

from __future__ import annotations

import math

import numpy as np

from pneumaquad.core.bank import ActuatorArrays, ActuatorBank
from pneumaquad.params import ActuatorParameters

from .builder import RobotJoints
from .coupling import (
    COUPLING_DTYPE,
    JOINT_CONTROL_DTYPE,
    LINKAGE_DTYPE,
    MODE_CLOSED_LOOP,
    MODE_OPEN_LOOP,
    MODE_UNCOMMANDED,
    SEAL_DTYPE,
    Controllers,
    Cylinders,
    StepSettings,
    StepTrace,
)
from .linkage import piston_position

__all__ = ["CylinderJoints", "seal_friction_row"]


def seal_friction_row(actuator: ActuatorParameters) -> np.ndarray:
    """Seal friction for MuJoCo's dry-friction constraint, a :data:`SEAL_DTYPE` record:
    Fs, Fc [N], vS [m/s], i, viscous coefficient [N s/m].

    The Stribeck-tanh and LuGre models give their Stribeck curve (eq 4.2.6) as the
    breakaway force and Cv as viscous damping; Coulomb(-viscous) give Fc (Fs from rest);
    the viscous model gives damping only (thesis 4.2.2).
    """
    f = actuator.friction
    row = np.zeros((), SEAL_DTYPE)
    row["stribeck_velocity"] = f.stribeck_velocity
    row["stribeck_exponent"] = f.stribeck_exponent
    if f.model in ("stribeck_tanh", "lugre", "coulomb_viscous"):
        row["static_force"] = f.static_force
        row["coulomb_force"] = f.coulomb_force
        row["viscous_coefficient"] = f.viscous_coefficient
        if f.model == "coulomb_viscous":
            row["stribeck_velocity"] = 1e-4
    elif f.model == "coulomb":
        row["static_force"] = row["coulomb_force"] = f.coulomb_force
    else:
        row["viscous_coefficient"] = f.damping_coefficient
    return row


class CylinderJoints:
    """The cylinders of a robot's simulated joints: an actuator bank and the joint side.

    Parameters
    ----------
    robot : RobotJoints
        Only its parameters, joint types, actuator parameters and linkages are read
        (no MuJoCo data is made).
    supply : {"ideal", "tank"}, optional
        Override of the actuator files' supply model (all cylinders share one supply).

    Attributes
    ----------
    bank : ActuatorBank
        The cylinders' parameters, state, supply and PID controllers.
    linkage, seal : ndarray (joints,)
        LINKAGE_DTYPE and SEAL_DTYPE records.
    settings : ndarray (joints,)
        JOINT_CONTROL_DTYPE: mode, pressure feedback and force tracking per joint.
    force_reference : ndarray (joints,)
        Force mean or set-point [N].
    reference_angles : ndarray (joints,)
        Joint-angle references [rad] of closed-loop joints.
    positions, velocities : ndarray (joints,)
        Piston readouts of the last control step [m], [m/s].
    coupling : ndarray (1,)
        COUPLING_DTYPE bookkeeping of the coupled step.
    cylinders, actuators, controllers, trace, step_settings
        The named bundles the compiled control step reads (views of the arrays above
        and of the bank's).
    """

    def __init__(self, robot: RobotJoints, supply: str | None = None) -> None:
        p = robot.parameters
        n = robot.joint_count
        actuators = [robot.actuators[t] for t in robot.joint_types]
        controllers = [getattr(p.controller, t) for t in robot.joint_types]
        self.bank = bank = ActuatorBank(actuators, controllers, supply_model=supply)
        self.step_settings = StepSettings(
            control_step=float(p.simulation.control_step),
            substeps=int(p.simulation.substeps),
            mujoco_friction=p.simulation.seal_friction == "mujoco")
        self._linkages = [robot.linkages[t] for t in robot.joint_types]
        self.linkage = np.zeros(n, LINKAGE_DTYPE)
        for i, link in enumerate(self._linkages):
            for field in LINKAGE_DTYPE.names:
                self.linkage[i][field] = getattr(link, field)
        self.seal = np.array([seal_friction_row(a) for a in actuators], dtype=SEAL_DTYPE)
        self.settings = np.zeros(n, JOINT_CONTROL_DTYPE)
        self.settings["force_feedback_gain"] = [c.force_feedback_gain for c in controllers]
        self.settings["force_feedback_time_constant"] = [
            c.force_feedback_time_constant for c in controllers]
        self.settings["mode"] = MODE_UNCOMMANDED
        self.force_reference = np.zeros(n)
        self.reference_angles = np.zeros(n)
        self.positions = np.zeros(n)
        self.velocities = np.zeros(n)
        self.coupling = np.zeros(1, COUPLING_DTYPE)
        # Named views for the compiled step (the same memory as the arrays above).
        self.cylinders = Cylinders(linkage=self.linkage, seal=self.seal)
        self.actuators: ActuatorArrays = bank.actuator_arrays
        self.controllers = Controllers(
            gains=bank.gains, gain_scale=bank.gain_scale, settings=self.settings,
            pid_state=bank.pid_state, force_reference=self.force_reference,
            reference_angles=self.reference_angles, open_loop_voltage=bank.open_loop_voltage)
        self.trace = StepTrace(commands=bank.commands, positions=self.positions,
                               velocities=self.velocities,
                               reference_positions=bank.references)

    @property
    def count(self) -> int:
        """Number of joints (cylinders)."""
        return self.bank.count

    # --- pistons and reset -----------------------------------------------------------
    def pistons_from_lengths(self, lengths: np.ndarray) -> np.ndarray:
        """Piston extensions [m] of pin-to-pin lengths [m], clipped to the stroke."""
        x = np.asarray(lengths, dtype=np.float64) - self.linkage["retracted_length"]
        return np.minimum(np.maximum(x, 0.0), self.bank.params["stroke"])

    def pistons_from_angles(self, angles: np.ndarray) -> np.ndarray:
        """Piston extensions [m] at joint angles [rad] by the linkage geometry (eq 5.2.1,
        5.2.3, 5.2.5), clipped to the stroke."""
        x = np.array([piston_position(link, angle)
                      for link, angle in zip(self._linkages, angles, strict=True)])
        return np.minimum(np.maximum(x, 0.0), self.bank.params["stroke"])

    def reset(self, angles: np.ndarray, positions: np.ndarray,
              chamber_pressure: float | None = None) -> None:
        """Cylinders at rest at piston ``positions`` [m] with every chamber at
        ``chamber_pressure`` [Pa] (midway between supply and exhaust by default), the
        supply and PIDs back to their start, force tracking off and the joint-angle
        references at ``angles`` [rad]; the chambers start at the present instant."""
        self.bank.reset(positions, chamber_pressure)
        self.coupling["pending"] = 0
        self.force_reference[:] = 0.0
        self.settings["force_tracking_gain"] = 0.0
        self.reference_angles[:] = angles

    # --- commands --------------------------------------------------------------------
    def command_angles(self, angles: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Closed-loop position control of ``joints`` (all by default) to ``angles`` [rad]."""
        index = slice(None) if joints is None else joints
        self.reference_angles[index] = angles
        self.settings["mode"][index] = MODE_CLOSED_LOOP

    def command_voltages(self, voltages: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Open-loop valve voltages [V] for ``joints`` (all by default)."""
        index = slice(None) if joints is None else joints
        self.bank.open_loop_voltage[index] = voltages
        self.settings["mode"][index] = MODE_OPEN_LOOP

    def release(self, joints: np.ndarray | None = None) -> None:
        """Hold the valves of ``joints`` at their offset (closed centre), uncommanded."""
        index = slice(None) if joints is None else joints
        self.settings["mode"][index] = MODE_UNCOMMANDED

    def track_forces(self, forces: np.ndarray, gain: float | np.ndarray,
                     joints: np.ndarray | None = None, stiffness: float = 1.0) -> None:
        """Force set-points [N] with tracking gain [V/N] and stiffness factor for
        ``joints``; see :meth:`RobotSimulation.track_forces
        <pneumaquad.robot.simulation.RobotSimulation.track_forces>`."""
        index = slice(None) if joints is None else joints
        if isinstance(gain, float | int):  # the walking controller's case, once per chunk
            valid = math.isfinite(gain) and gain >= 0.0
            gains: float | np.ndarray = float(gain)
        else:
            gains = np.broadcast_to(np.asarray(gain, dtype=float),
                                    self.settings["force_tracking_gain"][index].shape)
            valid = bool(np.all(gains >= 0.0) and np.all(np.isfinite(gains)))
        if not valid:
            raise ValueError(f"force tracking gain must be finite and >= 0, got {gain!r}")
        if not (math.isfinite(stiffness) and stiffness > 0.0):
            raise ValueError(f"stance stiffness factor must be finite and > 0, got "
                             f"{stiffness!r}")
        self.force_reference[index] = forces
        self.settings["force_tracking_gain"][index] = gains
        self.settings["force_stiffness"][index] = stiffness

    def stop_force_tracking(self, joints: np.ndarray | None = None) -> None:
        """Plain position control for ``joints`` (all by default); a tracking joint's
        force reference restarts from its present force."""
        selected = np.zeros(self.count, dtype=bool)
        selected[slice(None) if joints is None else joints] = True
        tracking = selected & (self.settings["force_tracking_gain"] > 0.0)
        self.settings["force_tracking_gain"][tracking] = 0.0
        self.force_reference[tracking] = self.bank.outputs["pneumatic_force"][tracking]
