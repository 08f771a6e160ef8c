"""The coupled simulation: a MuJoCo robot whose joints are driven by pneumatic cylinders.

:class:`RobotSimulation` holds the MuJoCo model and data and the robot's cylinders:
one :class:`~pneumaquad.core.bank.ActuatorBank` (parameters, chamber state, supply,
PID controllers) with the joint side of :class:`~pneumaquad.robot.joints.CylinderJoints`
(linkages, seal friction, joint-control settings and references). Each control step
(default 1 ms) computes MuJoCo's kinematics of the present state (``mj_step1``), reads
every piston position and velocity from the cylinder tendons, brings the chambers to the
present instant, runs all controllers, applies the cylinder forces and completes MuJoCo's
step (``mj_step2``), in one compiled call (:mod:`pneumaquad.robot.coupling`). Chunks of
steps run inside compiled code (:mod:`pneumaquad.robot.stepping`); Python sees the state
between chunks, for recording, gain scheduling and progress.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from pneumaquad.core.bank import ActuatorBank
from pneumaquad.gait.stability import STANCE_FORCE

from .builder import RobotModel, tibia_body_legs
from .coupling import MujocoBuffers, set_seal_friction
from .errors import SimulationDivergedError
from .joints import CylinderJoints, seal_friction_row
from .stepping import (
    MJ_FORCE_STAGE_ADDRESSES,
    MJ_STEP1_ADDRESS,
    MJ_STEP2_ADDRESS,
    MJ_STEP_ADDRESS,
    STATUS_ACTUATOR,
    STATUS_MUJOCO,
    MujocoStepper,
    advance_chunk,
    struct_address,
    unstable_quantities,
)

__all__ = [
    "RobotSimulation",
    "SimulationDivergedError",
    "seal_friction_row",
    "stance_swing_schedule",
]


GainSchedule = Callable[["RobotSimulation"], np.ndarray]

_NO_TABLE = np.zeros((0, 1))


def _step_addresses(model: mujoco.MjModel) -> np.ndarray:
    """``mj_step1``, the second half, ``mj_step``: the second half is ``mj_step2``, or for
    RK4 (which ``mj_step2`` does not integrate) a whole ``mj_step`` from the same state."""
    second = MJ_STEP_ADDRESS if model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4 \
        else MJ_STEP2_ADDRESS
    return np.array([MJ_STEP1_ADDRESS, second, MJ_STEP_ADDRESS, *MJ_FORCE_STAGE_ADDRESSES],
                    dtype=np.uint64)


def stance_swing_schedule(
    stance_scale: float, swing_scale: float, contact_force: float = STANCE_FORCE
) -> GainSchedule:
    """A gain schedule: PID gains × ``stance_scale`` on legs whose foot carries more than
    ``contact_force`` [N], × ``swing_scale`` on the others (evaluated between chunks)."""

    def schedule(simulation: RobotSimulation) -> np.ndarray:
        loaded = simulation.foot_normal_forces() > contact_force
        per_leg = np.where(loaded, stance_scale, swing_scale)
        return np.repeat(per_leg, 3)

    return schedule


class _Held:
    """A read-only attribute of :class:`RobotSimulation` that is an array or bundle held
    by its joints or their bank (the same object: write into it, never rebind it)."""

    def __init__(self, owner: str, name: str | None = None) -> None:
        self.owner, self.name = owner, name

    def __set_name__(self, cls: type, name: str) -> None:
        self.name = self.name or name

    def __get__(self, simulation: Any, cls: type | None = None) -> Any:
        if simulation is None:
            return self
        return getattr(getattr(simulation, self.owner), self.name)

    def __set__(self, simulation: Any, value: Any) -> None:
        raise AttributeError(f"{self.name} is held by the simulation's {self.owner}: write "
                             f"into it ({self.name}[...] = ...) or use a setter")


def _bad_actuator_quantity(simulation: RobotSimulation, cylinder: int) -> str:
    """Which of a cylinder's piston and chamber values is not finite."""
    values = {
        "piston position": simulation.positions[cylinder],
        "piston velocity": simulation.velocities[cylinder],
        "cap pressure": simulation.state[cylinder]["cap_pressure"],
        "rod pressure": simulation.state[cylinder]["rod_pressure"],
    }
    named = [name for name, value in values.items() if not math.isfinite(value)]
    return " and ".join(named) or "the chamber mass"


class RobotSimulation:
    """A robot model coupled to its cylinders, valves and joint controllers.

    Parameters
    ----------
    robot : RobotModel
        From :func:`pneumaquad.robot.build_robot`.
    supply : {"ideal", "tank"}, optional
        Override of the actuator files' supply model (all cylinders share one supply).
    """

    # The cylinders' arrays and the bundles the compiled step reads, held by the joints
    # (CylinderJoints) and their actuator bank (ActuatorBank): the same objects.
    params = _Held("bank")
    state = _Held("bank")
    supply = _Held("bank")
    outputs = _Held("bank")
    gains = _Held("bank")
    pid_state = _Held("bank")
    base_gain_scale = _Held("bank")
    gain_scale = _Held("bank")
    open_loop_voltage = _Held("bank")
    commands = _Held("bank")
    reference_positions = _Held("bank", "references")
    linkage = _Held("joints")
    seal = _Held("joints")
    joint_control = _Held("joints", "settings")
    force_reference = _Held("joints")
    reference_angles = _Held("joints")
    positions = _Held("joints")
    velocities = _Held("joints")
    coupling = _Held("joints")
    cylinders = _Held("joints")
    actuators = _Held("joints")
    controllers = _Held("joints")
    trace = _Held("joints")
    step_settings = _Held("joints")

    def __init__(self, robot: RobotModel, supply: str | None = None) -> None:
        self.robot = robot
        # The compiled step writes the seal friction into the model every step: each
        # simulation gets its own copy, so simulations built from one RobotModel (or the
        # model a renderer reads) never see each other's values.
        self.model = copy.copy(robot.model)
        self.data = d = mujoco.MjData(self.model)
        p = robot.parameters
        self.joints = CylinderJoints(robot, supply)
        self.bank: ActuatorBank = self.joints.bank
        self.mujoco = MujocoBuffers(  # views of MuJoCo's arrays for the compiled step
            tendon_length=d.ten_length, tendon_velocity=d.ten_velocity, control=d.ctrl,
            tendon_frictionloss=self.model.tendon_frictionloss,
            tendon_damping=self.model.tendon_damping, tendon_ids=robot.tendon_id,
            actuator_ids=robot.actuator_id)
        self.stepper = MujocoStepper(
            step_addresses=_step_addresses(self.model),
            model_address=struct_address(self.model), data_address=struct_address(d),
            warning_counts=d.warning.number, physics_steps=int(p.simulation.physics_steps))
        joints = self.joints
        self._bundles = (self.mujoco, joints.cylinders, joints.actuators, joints.controllers,
                         joints.trace, joints.coupling, joints.step_settings)
        self.gain_schedule: GainSchedule | None = None
        self._tibia_legs = tibia_body_legs(robot)
        controller = p.controller
        if controller.stance_gain_scale != 1.0 or controller.swing_gain_scale != 1.0:
            self.gain_schedule = stance_swing_schedule(
                controller.stance_gain_scale, controller.swing_gain_scale
            )
        placement = np.zeros(9)
        mujoco.mju_quat2Mat(placement, self.model.body_quat[robot.thorax_id])
        #: Rotation (3, 3) of the thorax's nominal placement (body frame → world at zero
        #: attitude, :func:`.recording.thorax_attitude`).
        self.thorax_placement = placement.reshape(3, 3)
        self.steps_taken = 0
        self.divergences = 0  # runs of step() that stopped on a diverged state
        self.set_pose(np.clip(np.zeros(robot.joint_count), robot.lower_limits(),
                              robot.upper_limits()))

    # --- settings (held once, in the bundles the compiled step reads) -----------------
    @property
    def control_step(self) -> float:
        """Control step [s]."""
        return self.step_settings.control_step

    @property
    def substeps(self) -> int:
        """Heun substeps of the pneumatic kernel per control step."""
        return self.step_settings.substeps

    @property
    def mujoco_friction(self) -> bool:
        """Whether the seal friction is MuJoCo's dry friction (else the actuator's law)."""
        return self.step_settings.mujoco_friction

    @property
    def physics_steps(self) -> int:
        """MuJoCo steps per control step."""
        return self.stepper.physics_steps

    # --- state -----------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def joint_angles(self) -> np.ndarray:
        """Joint angles [rad] of the simulated joints."""
        return self.data.qpos[self.robot.qpos_address].copy()

    def joint_velocities(self) -> np.ndarray:
        """Joint angular velocities [rad/s]."""
        return self.data.qvel[self.robot.dof_address].copy()

    def foot_positions(self) -> np.ndarray:
        """World positions of the feet [m], (legs, 3)."""
        return self.data.site_xpos[self.robot.foot_site_id].copy()

    def foot_normal_forces(self) -> np.ndarray:
        """Normal contact force on each foot (tibia) [N], summed over its contacts."""
        model, data = self.model, self.data
        forces = np.zeros(len(self.robot.legs))
        wrench = np.zeros(6)
        for index in range(data.ncon):
            contact = data.contact[index]
            for body in (model.geom_bodyid[contact.geom1], model.geom_bodyid[contact.geom2]):
                leg = self._tibia_legs.get(int(body))
                if leg is not None:
                    mujoco.mj_contactForce(model, data, index, wrench)
                    forces[leg] += abs(wrench[0])
        return forces

    def air_consumed(self) -> float:
        """Air drawn from the supply since the start [kg]."""
        return self.bank.air_consumed()

    def air_consumed_per_joint(self) -> np.ndarray:
        """Air drawn by each cylinder since the start [kg]."""
        return self.bank.air_consumed_per_actuator()

    def supply_pressure(self) -> float:
        """Tank pressure (tank supply) or regulated supply pressure [Pa]."""
        return self.bank.supply_pressure()

    def set_pose(
        self,
        joint_angles: np.ndarray,
        thorax_position: np.ndarray | None = None,
        thorax_quaternion: np.ndarray | None = None,
        chamber_pressure: float | None = None,
    ) -> None:
        """Place the robot at rest and reset actuators and controllers.

        Parameters
        ----------
        joint_angles : ndarray
            Angles [rad] of the simulated joints (clipped to their limits).
        thorax_position, thorax_quaternion : ndarray, optional
            Free-floating thorax pose (world [m], quaternion w-x-y-z).
        chamber_pressure : float, optional
            Absolute pressure of every chamber [Pa]; midway between supply and exhaust
            by default (a valve at rest near its centre).
        """
        robot = self.robot
        angles = np.clip(joint_angles, robot.lower_limits(), robot.upper_limits())
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[robot.qpos_address] = angles
        self.steps_taken = 0
        if robot.free:
            if thorax_position is not None:
                self.data.qpos[0:3] = thorax_position
            if thorax_quaternion is not None:
                self.data.qpos[3:7] = thorax_quaternion
        mujoco.mj_forward(self.model, self.data)
        joints = self.joints
        pistons = joints.pistons_from_lengths(self.data.ten_length[robot.tendon_id])
        joints.reset(angles, pistons, chamber_pressure)
        self.coupling["fresh"] = 1  # mj_forward above
        if self.mujoco_friction:  # the breakaway level at rest for the first step
            for index in range(robot.joint_count):
                set_seal_friction(self.mujoco, self.seal, index)
        self.step(0)  # piston readouts and forces of the new pose (compiles on first use)

    def restart_clock(self) -> None:
        """Start the simulated time (and the count of steps taken) again from 0 where the
        robot stands now; a regulated supply's air count too
        (:meth:`~pneumaquad.core.bank.ActuatorBank.restart_air_count`)."""
        self.data.time = 0.0
        self.steps_taken = 0
        self.bank.restart_air_count()

    # --- commands (the joints' own, :class:`~pneumaquad.robot.joints.CylinderJoints`) --
    def command_angles(self, angles: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Closed-loop position control of ``joints`` (all by default) to ``angles`` [rad]."""
        self.joints.command_angles(angles, joints)

    def command_voltages(self, voltages: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Open-loop valve voltages [V] for ``joints`` (all by default)."""
        self.joints.command_voltages(voltages, joints)

    def release(self, joints: np.ndarray | None = None) -> None:
        """Hold the valves of ``joints`` at their offset (closed centre), uncommanded."""
        self.joints.release(joints)

    def track_forces(self, forces: np.ndarray, gain: float | np.ndarray,
                     joints: np.ndarray | None = None, stiffness: float = 1.0) -> None:
        """Add force tracking to the position control of ``joints`` (all by default).

        Each cylinder then pushes with its set-point ``forces`` [N] plus a position spring
        of stiffness ``stiffness``·Kp / ``gain`` and a damper ``stiffness``·Kd / ``gain``
        (``gain`` [V/N] > 0; the PID's integral is off while it tracks):
        ``voltage = PD + gain · (F_set − F)``. Set-points hold until changed;
        :meth:`stop_force_tracking` returns to plain position control.
        """
        self.joints.track_forces(forces, gain, joints, stiffness)

    def stop_force_tracking(self, joints: np.ndarray | None = None) -> None:
        """Plain position control (integral back on) for ``joints`` (all by default).

        The force reference of a joint that was tracking restarts from its present force
        (the low-pass mean that pressure feedback, if configured, works about)."""
        self.joints.stop_force_tracking(joints)

    def force_tracking_gains(self) -> np.ndarray:
        """Per joint: force tracking gain [V/N] (0: plain position control)."""
        return self.joint_control["force_tracking_gain"].copy()

    def control_modes(self) -> np.ndarray:
        """Per joint: 0 uncommanded, 1 closed loop, 2 open loop."""
        return self.joint_control["mode"].copy()

    # --- stepping --------------------------------------------------------------------
    def step(self, count: int = 1, reference_table: np.ndarray | None = None,
             reference_start: int = 0) -> None:
        """Advance ``count`` control steps.

        Parameters
        ----------
        count : int
            Control steps.
        reference_table : ndarray (T, joints), optional
            Joint-angle references [rad] per control step; row ``reference_start + k`` is
            used at step k (the last row after the end).
        reference_start : int
            First row used.
        """
        if self.gain_schedule is not None:
            self.gain_scale[:] = self.base_gain_scale * self.gain_schedule(self)
        table = _NO_TABLE if reference_table is None else reference_table
        d = self.data
        start = self.time
        done, status, cylinder = advance_chunk(self.stepper, count, table, reference_start,
                                               *self._bundles)
        self.steps_taken += done
        if status == STATUS_MUJOCO:
            self.divergences += 1
            raise SimulationDivergedError(
                f"the simulation diverged between t = {start:.4g} s and {self.time:.4g} s: "
                f"{unstable_quantities(d)} went non-finite or huge in MuJoCo (the run "
                "stops here; what was recorded before is kept); try a smaller "
                "simulation.control_step, more substeps or softer contacts",
                time=self.time,
            )
        if status == STATUS_ACTUATOR:
            self.divergences += 1
            raise SimulationDivergedError(
                f"the simulation diverged at t = {self.time:.4g} s: "
                f"{_bad_actuator_quantity(self, cylinder)} of cylinder "
                f"{self.robot.joint_names[cylinder]} went non-finite (the run stops here; "
                "what was recorded before is kept)",
                time=self.time,
            )

    # --- snapshots -------------------------------------------------------------------
    _SNAPSHOT_ARRAYS = ("state", "supply", "outputs", "pid_state", "force_reference",
                        "coupling", "commands", "positions", "velocities",
                        "reference_positions", "reference_angles", "joint_control",
                        "open_loop_voltage", "gain_scale")

    def snapshot(self, into: dict[str, object] | None = None) -> dict[str, object]:
        """A copy of everything :meth:`step` changes (MuJoCo data, the seal friction it
        writes into the model, actuator and controller state), for :meth:`restore`;
        written into an earlier snapshot ``into`` when given (no allocation)."""
        tendons = self.robot.tendon_id
        if into is None:
            into = {name: getattr(self, name).copy() for name in self._SNAPSHOT_ARRAYS}
            into["data"] = mujoco.MjData(self.model)
            into["frictionloss"] = self.model.tendon_frictionloss[tendons].copy()
            into["damping"] = self.model.tendon_damping[tendons].copy()
        else:
            for name in self._SNAPSHOT_ARRAYS:
                into[name][...] = getattr(self, name)  # type: ignore[index]
            into["frictionloss"][...] = self.model.tendon_frictionloss[tendons]  # type: ignore[index]
            into["damping"][...] = self.model.tendon_damping[tendons]  # type: ignore[index]
        mujoco.mj_copyData(into["data"], self.model, self.data)
        into["steps_taken"] = self.steps_taken
        return into

    def restore(self, snapshot: dict[str, object]) -> None:
        """Return to a :meth:`snapshot` (the divergence counter is kept)."""
        mujoco.mj_copyData(self.data, self.model, snapshot["data"])
        for name in self._SNAPSHOT_ARRAYS:
            getattr(self, name)[...] = snapshot[name]
        tendons = self.robot.tendon_id
        self.model.tendon_frictionloss[tendons] = snapshot["frictionloss"]
        self.model.tendon_damping[tendons] = snapshot["damping"]
        self.steps_taken = int(snapshot["steps_taken"])  # type: ignore[arg-type]

    # --- readouts --------------------------------------------------------------------
    def chamber_pressures(self) -> np.ndarray:
        """(joints, 2) cap and rod pressures [Pa], absolute."""
        return self.bank.chamber_pressures()

    def cylinder_forces(self) -> np.ndarray:
        """Net pneumatic force of each cylinder [N] (eq 4.1.11 without friction)."""
        return self.bank.forces()

    def atmospheric_pressure(self) -> float:
        """Atmospheric pressure [Pa] of the actuator files."""
        return self.bank.atmospheric_pressure()
