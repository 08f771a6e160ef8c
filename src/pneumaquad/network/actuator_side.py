"""The actuator side of the networked co-simulation: controllers and pneumatics, no MuJoCo.

The thesis ran the valve, cylinder and controller models in Simulink on an xPC target and
sent joint commands to the dynamics over UDP (Daepp 2011, ch. 5.1-5.2). Here
:class:`ActuatorSide` holds the robot's cylinders as
:class:`~pneumaquad.robot.simulation.RobotSimulation` does, through the same
:class:`~pneumaquad.robot.joints.CylinderJoints` (one
:class:`~pneumaquad.core.bank.ActuatorBank` plus linkages, seal friction and joint-control
settings from the robot's parameters and linkage geometry), without any MuJoCo data. Each
:meth:`ActuatorSide.forces` call is one control step of
:func:`~pneumaquad.robot.coupling.robot_control_step` fed with the piston positions and
velocities of a ``STATE``; the returned cylinder forces go back as a ``FORCE_COMMAND``.

Differences to the in-process run: the controller reads the piston position as
``(x + l2) - l2`` (the kernel works on tendon lengths), which can differ from ``x`` in the
last bit; the stance/swing gain schedule (which needs foot contact forces) is not
applied; without the ``STATE``'s pistons, :meth:`ActuatorSide.set_pose` places them by
the linkage's closed form, which differs from MuJoCo's tendon lengths in the last bits
(so the run starts from the dynamics' pistons, as :meth:`ActuatorClient.connect
<pneumaquad.network.client.ActuatorClient.connect>` does, to match it bit for bit).
"""

from __future__ import annotations

import numpy as np

from pneumaquad.core.bank import ActuatorBank
from pneumaquad.network.state import StateMessage
from pneumaquad.robot.builder import RobotJoints
from pneumaquad.robot.coupling import MujocoBuffers, robot_control_step
from pneumaquad.robot.joints import CylinderJoints

__all__ = ["ActuatorSide"]


class ActuatorSide:
    """Cylinders, valves and joint controllers of a robot, driven by received states.

    Parameters
    ----------
    robot
        From :func:`pneumaquad.robot.builder.robot_joints` (no MuJoCo model is needed)
        or :func:`~pneumaquad.robot.builder.build_robot` (the same parameters as the
        dynamics side); only its parameters, joint list, actuator files and linkages are
        read: no MuJoCo data is made.
    supply
        Optional supply-model override (``"ideal"`` or ``"tank"``).

    Raises
    ------
    ValueError
        ``simulation.seal_friction = "actuator"``: that friction is applied through the
        MuJoCo tendon damping, which a ``FORCE_COMMAND`` cannot carry.
    """

    def __init__(self, robot: RobotJoints, supply: str | None = None) -> None:
        if robot.parameters.simulation.seal_friction != "mujoco":
            raise ValueError(
                'the networked actuator side needs simulation.seal_friction = "mujoco" '
                "(the dynamics side computes the seal friction from the piston velocity)")
        self.robot = robot
        self.joints = CylinderJoints(robot, supply)
        self.bank: ActuatorBank = self.joints.bank
        self.joint_count = robot.joint_count
        self.control_step = self.joints.step_settings.control_step
        self.substeps = self.joints.step_settings.substeps
        count = self.joint_count
        # This side's own tendon arrays, filled from each STATE (no MuJoCo here).
        self._tendons = MujocoBuffers(
            tendon_length=np.zeros(count), tendon_velocity=np.zeros(count),
            control=np.zeros(count), tendon_frictionloss=np.zeros(count),
            tendon_damping=np.zeros(count), tendon_ids=np.arange(count),
            actuator_ids=np.arange(count))
        self._retracted = self.joints.linkage["retracted_length"].copy()
        self.steps_taken = 0
        self.set_pose(np.zeros(count))

    # --- set-up and commands -----------------------------------------------------------
    def set_pose(self, joint_angles: np.ndarray, chamber_pressure: float | None = None,
                 piston_positions: np.ndarray | None = None) -> None:
        """Reset actuators and controllers for a robot at rest at ``joint_angles`` [rad].

        Parameters
        ----------
        joint_angles
            Joint angles [rad] (clipped to the joint limits): the references of the
            closed-loop joints.
        chamber_pressure
            Absolute pressure of every chamber [Pa]; midway between supply and exhaust
            by default (as :meth:`RobotSimulation.set_pose
            <pneumaquad.robot.simulation.RobotSimulation.set_pose>`).
        piston_positions
            Piston extensions [m], e.g. a ``STATE``'s (the dynamics' own pistons); by
            default from ``joint_angles`` through the linkage geometry.
        """
        robot = self.robot
        angles = np.clip(np.asarray(joint_angles, dtype=float), robot.lower_limits(),
                         robot.upper_limits())
        if piston_positions is None:
            pistons = self.joints.pistons_from_angles(angles)
        else:
            pistons = np.minimum(np.maximum(np.asarray(piston_positions, dtype=float), 0.0),
                                 self.bank.params["stroke"])
        self.joints.reset(angles, pistons, chamber_pressure)
        self.steps_taken = 0

    def command_angles(self, angles: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Closed-loop position control of ``joints`` (all by default) to ``angles`` [rad]."""
        self.joints.command_angles(angles, joints)

    def command_voltages(self, voltages: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Open-loop valve voltages [V] for ``joints`` (all by default)."""
        self.joints.command_voltages(voltages, joints)

    def release(self, joints: np.ndarray | None = None) -> None:
        """Hold the valves of ``joints`` at their offset (closed centre)."""
        self.joints.release(joints)

    @property
    def reference_angles(self) -> np.ndarray:
        """Joint-angle references [rad] (a view; closed-loop joints follow it)."""
        return self.joints.reference_angles

    # --- the control step --------------------------------------------------------------
    def forces(self, state: StateMessage) -> np.ndarray:
        """One control step of controllers and actuators at the pistons of ``state``.

        Parameters
        ----------
        state
            The dynamics' state; its piston positions [m] and velocities [m/s] are used.

        Returns
        -------
        numpy.ndarray
            Cylinder forces [N] (positive extends the piston), one per joint, to apply
            during the next control step.
        """
        j = self.joints
        positions = np.asarray(state.piston_positions, dtype=np.float64)
        if positions.size != self.joint_count:
            raise ValueError(f"STATE has {positions.size} joints, the robot {self.joint_count}")
        tendons = self._tendons
        np.add(positions, self._retracted, out=tendons.tendon_length)
        tendons.tendon_velocity[:] = state.piston_velocities
        robot_control_step(tendons, j.cylinders, j.actuators, j.controllers, j.trace,
                           j.coupling, j.step_settings)
        self.steps_taken += 1
        return tendons.control.copy()

    # --- readouts ----------------------------------------------------------------------
    def valve_commands(self) -> np.ndarray:
        """Valve voltages of the last step [V]."""
        return self.bank.commands.copy()

    def chamber_pressures(self) -> np.ndarray:
        """(joints, 2) cap and rod pressures [Pa], absolute."""
        return self.bank.chamber_pressures()

    def air_consumed(self) -> float:
        """Air drawn from the supply since the start [kg]."""
        return self.bank.air_consumed()
