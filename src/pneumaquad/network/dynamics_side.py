"""The dynamics side of the networked co-simulation: MuJoCo, one control step per command.

The thesis ran the rigid-body dynamics (SrLib) on a PC that received joint torques over
UDP, stepped once and sent the state back (Daepp 2011, ch. 5.1, App. C.2.4). Here the
dynamics accepts one of three command kinds (``docs/protocol.md``):

``"valve"``
    Valve input voltages [V]. The actuators are simulated on this side: a
    :class:`~pneumaquad.robot.simulation.RobotSimulation` runs every joint open loop at
    the received voltages, so any external UDP client can drive the pneumatic robot.
``"force"``
    Cylinder forces [N] from an external actuator model (the thesis's split). Only
    MuJoCo runs here: the forces go into ``data.ctrl`` and the seal friction is computed
    on this side exactly as :func:`~pneumaquad.robot.coupling.robot_control_step` does
    with ``simulation.seal_friction = "mujoco"`` (Stribeck breakaway force at the current
    tendon velocity as the tendon's dry friction, Cv as its damping).
``"torque"``
    Joint torques [N m] into ``qfrc_applied`` of the joint degrees of freedom; cylinder
    motors and seal friction are zero (rigid-body dynamics only, like SrLib).

Safe state (:meth:`DynamicsSide.engage_safe_state`): valve mode holds every valve at its
offset voltage (closed centre, the chambers hold their air); force and torque modes apply
zero force / torque (seal friction stays, it is physical).

Command limits (:meth:`DynamicsSide.apply`, ``docs/protocol.md``): nothing outside what the
actuators can physically deliver reaches the model. Per joint, from its packed actuator
parameters: voltages within the valve's [min_voltage, max_voltage]; forces within
[pe·A_cap − ps·A_rod − patm·A_section, ps·A_cap − pe·A_rod − patm·A_section] (supply
pressure ps on one side of the piston, exhaust pe on the other, eq 4.1.11); torques
within ± the larger of those force magnitudes times the largest moment arm of the joint's
linkage over its range. Values outside are clamped and counted; non-finite values are
refused.
"""

from __future__ import annotations

import mujoco
import numpy as np

from pneumaquad.network.state import StateMessage, StatusFlag
from pneumaquad.robot.builder import RobotModel
from pneumaquad.robot.coupling import set_seal_friction
from pneumaquad.robot.errors import SimulationDivergedError
from pneumaquad.robot.linkage import moment_arm
from pneumaquad.robot.simulation import RobotSimulation
from pneumaquad.robot.stepping import (
    UNSTABLE_WARNINGS,
    begin_step,
    bring_to_present,
    complete_step,
    unstable_quantities,
)

__all__ = ["COMMAND_KINDS", "DynamicsSide", "piston_readout"]

COMMAND_KINDS = ("valve", "force", "torque")


def piston_readout(model_data: mujoco.MjData, robot: RobotModel, retracted: np.ndarray,
                   stroke: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Piston positions [m] (clipped to the stroke) and velocities [m/s] from the tendons.

    These are the values the in-process controllers read: MuJoCo's tendon lengths and
    velocities of the present state (the dynamics side keeps ``mj_step1`` done).
    """
    lengths = model_data.ten_length[robot.tendon_id]
    positions = np.minimum(np.maximum(lengths - retracted, 0.0), stroke)
    return positions, model_data.ten_velocity[robot.tendon_id].copy()


class DynamicsSide:
    """MuJoCo robot advanced one control step per received command.

    Parameters
    ----------
    robot
        From :func:`pneumaquad.robot.builder.build_robot`; it is not written to (the
        simulation steps its own copy of ``robot.model``).
    command_kind
        ``"valve"`` [V], ``"force"`` [N] or ``"torque"`` [N m].

    Raises
    ------
    ValueError
        Unknown command kind, or force mode with ``simulation.seal_friction =
        "actuator"`` (that friction law needs the actuator's internal state).

    Attributes
    ----------
    voltage_limits, force_limits, torque_limits : numpy.ndarray
        Shape (N, 2): lowest and highest valve voltage [V], cylinder force [N] (positive
        extends) and joint torque [N m] each joint's actuator can deliver.
    command_limits : numpy.ndarray
        The limits of this side's command kind; :meth:`apply` clamps to them.
    command_clamped : bool
        Whether the last applied command had a value outside the limits.
    clamped_commands, clamped_values : int
        Commands with at least one value clamped, and values clamped [count].
    """

    def __init__(self, robot: RobotModel, command_kind: str) -> None:
        if command_kind not in COMMAND_KINDS:
            raise ValueError(f"command kind {command_kind!r} should be one of {COMMAND_KINDS}")
        if command_kind == "force" and robot.parameters.simulation.seal_friction != "mujoco":
            raise ValueError(
                'force commands need simulation.seal_friction = "mujoco": with "actuator" '
                "the seal friction depends on the actuator's internal state, which the "
                "dynamics side does not have; run the actuators here (valve commands) or "
                'set simulation.seal_friction="mujoco"')
        self.robot = robot
        self.command_kind = command_kind
        self.simulation = RobotSimulation(robot)  # arrays, pose and, in valve mode, actuators
        self.model = self.simulation.model  # the simulation's own copy of robot.model
        self.data = self.simulation.data
        self.joint_count = robot.joint_count
        self.control_step = self.simulation.control_step
        self.physics_steps = self.simulation.physics_steps
        self.command = np.zeros(self.joint_count)
        self.safe = False
        #: Set when a step diverged (the step was undone; see :meth:`step`).
        self.diverged = False
        self._last_good: dict[str, object] | None = None
        self._retracted = self.simulation.linkage["retracted_length"].copy()
        params = self.simulation.params
        self._stroke = params["stroke"].copy()
        self.voltage_limits = np.column_stack([params["min_voltage"], params["max_voltage"]])
        supply, exhaust = params["supply_pressure"], params["exhaust_pressure"]
        atmosphere = params["atmospheric_pressure"]
        cap, rod, section = params["cap_area"], params["rod_area"], params["rod_cross_section"]
        extending = supply * cap - exhaust * rod - atmosphere * section
        retracting = exhaust * cap - supply * rod - atmosphere * section
        self.force_limits = np.column_stack([retracting, extending])
        lowers, uppers = robot.lower_limits(), robot.upper_limits()
        largest_arm = np.array([
            np.max(np.abs(moment_arm(robot.linkages[kind], np.linspace(low, high, 181))))
            for kind, low, high in zip(robot.joint_types, lowers, uppers, strict=True)])
        largest_torque = np.maximum(np.abs(extending), np.abs(retracting)) * largest_arm
        self.torque_limits = np.column_stack([-largest_torque, largest_torque])
        self.command_limits = {"valve": self.voltage_limits, "force": self.force_limits,
                               "torque": self.torque_limits}[command_kind]
        self.command_clamped = False
        self.clamped_commands = 0
        self.clamped_values = 0
        if command_kind == "torque":
            self.model.tendon_frictionloss[robot.tendon_id] = 0.0
            self.model.tendon_damping[robot.tendon_id] = 0.0
        self.engage_safe_state()
        self.safe = False

    # --- pose and commands -------------------------------------------------------------
    def set_pose(self, joint_angles: np.ndarray) -> None:
        """Place the robot at rest at ``joint_angles`` [rad] (actuators reset)."""
        self.simulation.set_pose(np.asarray(joint_angles, dtype=float))
        self.diverged = False

    def apply(self, values: np.ndarray) -> None:
        """Hold ``values`` (one per joint: [V], [N] or [N m]) from the next step on.

        Values outside :attr:`command_limits` are clamped to them; such a command is
        counted (:attr:`clamped_commands`, :attr:`clamped_values`) and flagged
        (:attr:`command_clamped`). Leaves the safe state.

        Raises
        ------
        ValueError
            Wrong number of values, or a NaN / infinite value (the held command is kept).
        """
        values = np.asarray(values, dtype=np.float64).reshape(-1)
        if values.size != self.joint_count:
            raise ValueError(f"{values.size} command values for {self.joint_count} joints")
        finite = np.isfinite(values)
        if not finite.all():
            joints = [self.robot.joint_names[i] for i in np.flatnonzero(~finite)]
            raise ValueError(f"non-finite {self.command_kind} command for {', '.join(joints)}; "
                             "the command is refused")
        limited = np.clip(values, self.command_limits[:, 0], self.command_limits[:, 1])
        clamped = np.count_nonzero(limited != values)
        self.command_clamped = clamped > 0
        if clamped:
            self.clamped_commands += 1
            self.clamped_values += int(clamped)
        self.command[:] = limited
        self.safe = False
        if self.command_kind == "valve":
            self.simulation.command_voltages(self.command)

    def engage_safe_state(self) -> None:
        """Valves at their offset (closed centre) in valve mode; zero force / torque else."""
        self.safe = True
        self.command[:] = 0.0
        if self.command_kind == "valve":
            self.simulation.release()

    # --- stepping ----------------------------------------------------------------------
    def step(self) -> None:
        """Advance exactly one control step with the held command.

        The same order as the in-process coupling (:mod:`pneumaquad.robot.stepping`):
        the command acts from the present state, whose kinematics (``mj_step1``) the last
        ``STATE`` reported; ``mj_step2`` completes the step and ``mj_step1`` prepares the
        kinematics of the next ``STATE``.

        Raises
        ------
        SimulationDivergedError
            The state went non-finite or huge (MuJoCo's unstable-state warnings, or a
            cylinder's chambers in valve mode). The step is undone: the last good state
            is kept, :attr:`diverged` is set and the safe state engaged.
        """
        self._last_good = self.simulation.snapshot(self._last_good)
        try:
            self._step()
        except SimulationDivergedError:
            self.simulation.restore(self._last_good)
            self.diverged = True
            self.engage_safe_state()
            raise

    def _step(self) -> None:
        if self.command_kind == "valve":
            self.simulation.step(1)
            return
        data, robot = self.data, self.robot
        coupling = self.simulation.coupling
        before = data.warning.number[UNSTABLE_WARNINGS].copy()
        stepper = self.simulation.stepper
        begin_step(stepper, coupling)  # (done by the last step, which the STATE reported)
        if self.command_kind == "force":
            data.ctrl[robot.actuator_id] = self.command
            # The function robot_control_step uses, so both sides agree bit for bit.
            for index in range(robot.joint_count):
                set_seal_friction(self.simulation.mujoco, self.simulation.seal, index)
        else:
            data.ctrl[robot.actuator_id] = 0.0
            data.qfrc_applied[robot.dof_address] = self.command
        complete_step(stepper, coupling)
        bring_to_present(stepper, coupling)  # the kinematics and forces of the next STATE
        self.simulation.steps_taken += 1
        if np.any(data.warning.number[UNSTABLE_WARNINGS] != before):
            self.simulation.divergences += 1
            raise SimulationDivergedError(
                f"the simulation diverged at t = {self.time:.4g} s: "
                f"{unstable_quantities(data)} went non-finite or huge in MuJoCo",
                time=self.time)

    # --- readouts ----------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return float(self.data.time)

    def state(self, answered_sequence: int = -1,
              status: StatusFlag = StatusFlag.NONE) -> StateMessage:
        """The current state as a ``STATE`` payload (piston values: see :func:`piston_readout`)."""
        data, robot = self.data, self.robot
        positions, velocities = piston_readout(data, robot, self._retracted, self._stroke)
        if self.safe:
            status |= StatusFlag.SAFE_STATE
        if robot.free:
            thorax, quaternion = data.qpos[0:3].copy(), data.qpos[3:7].copy()
        else:
            thorax = data.xpos[robot.thorax_id].copy()
            quaternion = data.xquat[robot.thorax_id].copy()
        return StateMessage(
            simulation_time=self.time,
            joint_angles=data.qpos[robot.qpos_address].copy(),
            joint_velocities=data.qvel[robot.dof_address].copy(),
            piston_positions=positions,
            piston_velocities=velocities,
            thorax_position=thorax,
            thorax_quaternion=quaternion,
            answered_sequence=answered_sequence,
            status=status,
        )

    # --- recording ---------------------------------------------------------------------
    def recording_columns(self) -> tuple[str, ...]:
        """Columns of :meth:`recording_row` (``quantity [unit]``)."""
        if self.command_kind == "valve":
            from pneumaquad.robot.recording import recording_columns

            return recording_columns(self.simulation)
        unit = "[N]" if self.command_kind == "force" else "[N m]"
        columns = ["time [s]"]
        for joint in self.robot.joint_names:
            columns += [f"{joint} angle [rad]", f"{joint} angular velocity [rad/s]",
                        f"{joint} piston position [m]", f"{joint} piston velocity [m/s]",
                        f"{joint} {self.command_kind} command {unit}"]
        columns += ["thorax x [m]", "thorax y [m]", "thorax z [m]", "thorax qw [-]",
                    "thorax qx [-]", "thorax qy [-]", "thorax qz [-]"]
        return tuple(columns)

    def recording_row(self) -> np.ndarray:
        """One row of the current state, layout of :meth:`recording_columns`."""
        if self.command_kind == "valve":
            from pneumaquad.robot.recording import recording_row

            return recording_row(self.simulation, self.simulation.reference_angles)
        state = self.state()
        per_joint = np.column_stack([state.joint_angles, state.joint_velocities,
                                     state.piston_positions, state.piston_velocities,
                                     self.command]).ravel()
        return np.concatenate([[state.simulation_time], per_joint, state.thorax_position,
                               state.thorax_quaternion])
