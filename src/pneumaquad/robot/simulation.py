"""The coupled simulation: a MuJoCo robot whose joints are driven by pneumatic cylinders.

:class:`RobotSimulation` holds the MuJoCo model and data, the packed actuator arrays of
all cylinders and their controllers. Each control step (default 1 ms) computes MuJoCo's
kinematics of the present state (``mj_step1``), reads every piston position and velocity
from the cylinder tendons, brings the chambers to the present instant, runs all
controllers, applies the cylinder forces and completes MuJoCo's step (``mj_step2``), in
one compiled call (:mod:`pneumaquad.robot.coupling`). Chunks of steps run inside compiled code
(:mod:`pneumaquad.robot.stepping`); Python sees the state between chunks, for
recording, gain scheduling and progress.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable

import mujoco
import numpy as np

from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.control.pid import PID_GAINS_DTYPE, controller_gains, new_pid_state
from pneumaquad.core.layout import ACTUATOR_STATE_DTYPE, SUPPLY_TANK
from pneumaquad.gait.stability import STANCE_FORCE
from pneumaquad.params import ActuatorParameters

from .builder import RobotModel
from .coupling import (
    COUPLING_DTYPE,
    JOINT_CONTROL_DTYPE,
    LINKAGE_DTYPE,
    MODE_CLOSED_LOOP,
    MODE_OPEN_LOOP,
    MODE_UNCOMMANDED,
    SEAL_DTYPE,
    ActuatorArrays,
    Controllers,
    Cylinders,
    MujocoBuffers,
    StepSettings,
    StepTrace,
    set_seal_friction,
)
from .errors import SimulationDivergedError
from .stepping import (
    MJ_FORCE_STAGE_ADDRESSES,
    MJ_STEP1_ADDRESS,
    MJ_STEP2_ADDRESS,
    MJ_STEP_ADDRESS,
    STATUS_ACTUATOR,
    STATUS_MUJOCO,
    MujocoStepper,
    advance_chunk,
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

    def __init__(self, robot: RobotModel, supply: str | None = None) -> None:
        self.robot = robot
        # The compiled step writes the seal friction into the model every step: each
        # simulation gets its own copy, so simulations built from one RobotModel (or the
        # model a renderer reads) never see each other's values.
        self.model = copy.copy(robot.model)
        self.data = mujoco.MjData(self.model)
        p = robot.parameters
        n = robot.joint_count
        self.step_settings = StepSettings(
            control_step=float(p.simulation.control_step),
            substeps=int(p.simulation.substeps),
            mujoco_friction=p.simulation.seal_friction == "mujoco")
        actuators = [robot.actuators[t] for t in robot.joint_types]
        self.params = pack_parameter_array(actuators)
        first = robot.actuators["alpha"]
        if supply is not None and supply != first.supply.model:
            first = first.model_copy(update={"supply": first.supply.model_copy(
                update={"model": supply})})
        self.supply = supply_state(first)
        self._initial_supply = self.supply.copy()
        self.outputs = new_outputs(n)
        self.linkage = np.zeros(n, LINKAGE_DTYPE)
        for i, joint_type in enumerate(robot.joint_types):
            link = robot.linkages[joint_type]
            for field in LINKAGE_DTYPE.names:
                self.linkage[i][field] = getattr(link, field)
        self.seal = np.array([seal_friction_row(a) for a in actuators], dtype=SEAL_DTYPE)
        controllers = [getattr(p.controller, t) for t in robot.joint_types]
        self.gains = np.array(
            [controller_gains(c, a.valve) for c, a in zip(controllers, actuators, strict=True)],
            dtype=PID_GAINS_DTYPE,
        )
        self.base_gain_scale = np.array([c.gain_scale for c in controllers])
        self.gain_scale = self.base_gain_scale.copy()
        self.joint_control = np.zeros(n, JOINT_CONTROL_DTYPE)
        self.joint_control["force_feedback_gain"] = [c.force_feedback_gain for c in controllers]
        self.joint_control["force_feedback_time_constant"] = [
            c.force_feedback_time_constant for c in controllers]
        self.joint_control["mode"] = MODE_UNCOMMANDED
        self.pid_state = new_pid_state(n)
        self.force_reference = np.zeros(n)
        self.reference_angles = np.zeros(n)
        self.open_loop_voltage = self.params["offset_voltage"].copy()
        self.commands = self.params["offset_voltage"].copy()
        self.positions = np.zeros(n)
        self.velocities = np.zeros(n)
        self.reference_positions = np.zeros(n)
        self.state = np.zeros(n, ACTUATOR_STATE_DTYPE)
        self.coupling = np.zeros(1, COUPLING_DTYPE)
        d = self.data
        # Named views of the arrays above for the compiled step (the same memory).
        self.mujoco = MujocoBuffers(
            tendon_length=d.ten_length, tendon_velocity=d.ten_velocity, control=d.ctrl,
            tendon_frictionloss=self.model.tendon_frictionloss,
            tendon_damping=self.model.tendon_damping, tendon_ids=robot.tendon_id,
            actuator_ids=robot.actuator_id)
        self.cylinders = Cylinders(linkage=self.linkage, seal=self.seal)
        self.actuators = ActuatorArrays(params=self.params, state=self.state,
                                        supply=self.supply, outputs=self.outputs)
        self.controllers = Controllers(
            gains=self.gains, gain_scale=self.gain_scale, settings=self.joint_control,
            pid_state=self.pid_state, force_reference=self.force_reference,
            reference_angles=self.reference_angles, open_loop_voltage=self.open_loop_voltage)
        self.trace = StepTrace(commands=self.commands, positions=self.positions,
                               velocities=self.velocities,
                               reference_positions=self.reference_positions)
        self.stepper = MujocoStepper(
            step_addresses=_step_addresses(self.model), model_address=self.model._address,
            data_address=d._address, warning_counts=d.warning.number,
            physics_steps=int(p.simulation.physics_steps))
        self.gain_schedule: GainSchedule | None = None
        self._tibia_leg = {
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, f"{leg}_tibia"): index
            for index, leg in enumerate(robot.legs)
        }
        controller = p.controller
        if controller.stance_gain_scale != 1.0 or controller.swing_gain_scale != 1.0:
            self.gain_schedule = stance_swing_schedule(
                controller.stance_gain_scale, controller.swing_gain_scale
            )
        self.steps_taken = 0
        self.divergences = 0  # runs of step() that stopped on a diverged state
        self.set_pose(np.clip(np.zeros(n), robot.lower_limits(), robot.upper_limits()))

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
                leg = self._tibia_leg.get(int(body))
                if leg is not None:
                    mujoco.mj_contactForce(model, data, index, wrench)
                    forces[leg] += abs(wrench[0])
        return forces

    def air_consumed(self) -> float:
        """Air drawn from the supply since the start [kg]."""
        return float(self.supply[0]["drawn_mass"])

    def air_consumed_per_joint(self) -> np.ndarray:
        """Air drawn by each cylinder since the start [kg]."""
        return self.state["air_consumed"].copy()

    def supply_pressure(self) -> float:
        """Tank pressure (tank supply) or regulated supply pressure [Pa]."""
        supply = self.supply[0]
        if supply["model"] == SUPPLY_TANK:
            return float(supply["tank_pressure"])
        return float(self.params[0]["supply_pressure"])

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
        self.supply[:] = self._initial_supply
        self.steps_taken = 0
        if robot.free:
            if thorax_position is not None:
                self.data.qpos[0:3] = thorax_position
            if thorax_quaternion is not None:
                self.data.qpos[3:7] = thorax_quaternion
        mujoco.mj_forward(self.model, self.data)
        lengths = self.data.ten_length[robot.tendon_id]
        for i in range(robot.joint_count):
            p = self.params[i]
            retracted = self.linkage[i]['retracted_length']
            position = min(max(lengths[i] - retracted, 0.0), p["stroke"])
            pressure = chamber_pressure
            if pressure is None:
                pressure = 0.5 * (p["supply_pressure"] + p["exhaust_pressure"])
            initial_state(p, position, pressure, pressure, out=self.state[i])
        self.pid_state[:] = 0.0
        self.outputs[:] = 0.0
        self.coupling["pending"] = 0  # the chambers start at the present instant
        self.coupling["fresh"] = 1  # mj_forward above
        if self.mujoco_friction:  # the breakaway level at rest for the first step
            for index in range(robot.joint_count):
                set_seal_friction(self.mujoco, self.seal, index)
        self.force_reference[:] = 0.0
        self.joint_control["force_tracking_gain"] = 0.0
        self.reference_angles[:] = angles
        self.step(0)  # piston readouts and forces of the new pose (compiles on first use)

    # --- commands --------------------------------------------------------------------
    def command_angles(self, angles: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Closed-loop position control of ``joints`` (all by default) to ``angles`` [rad]."""
        index = slice(None) if joints is None else joints
        self.reference_angles[index] = angles
        self.joint_control["mode"][index] = MODE_CLOSED_LOOP

    def command_voltages(self, voltages: np.ndarray, joints: np.ndarray | None = None) -> None:
        """Open-loop valve voltages [V] for ``joints`` (all by default)."""
        index = slice(None) if joints is None else joints
        self.open_loop_voltage[index] = voltages
        self.joint_control["mode"][index] = MODE_OPEN_LOOP

    def release(self, joints: np.ndarray | None = None) -> None:
        """Hold the valves of ``joints`` at their offset (closed centre), uncommanded."""
        index = slice(None) if joints is None else joints
        self.joint_control["mode"][index] = MODE_UNCOMMANDED

    def track_forces(self, forces: np.ndarray, gain: float | np.ndarray,
                     joints: np.ndarray | None = None, stiffness: float = 1.0) -> None:
        """Add force tracking to the position control of ``joints`` (all by default).

        Each cylinder then pushes with its set-point ``forces`` [N] plus a position spring
        of stiffness ``stiffness``·Kp / ``gain`` and a damper ``stiffness``·Kd / ``gain``
        (``gain`` [V/N] > 0; the PID's integral is off while it tracks):
        ``voltage = PD + gain · (F_set − F)``. Set-points hold until changed;
        :meth:`stop_force_tracking` returns to plain position control.
        """
        index = slice(None) if joints is None else joints
        gains = np.broadcast_to(np.asarray(gain, dtype=float),
                                self.joint_control["force_tracking_gain"][index].shape)
        if np.any(gains < 0.0) or not np.all(np.isfinite(gains)):
            raise ValueError(f"force tracking gain must be finite and >= 0, got {gain!r}")
        if not (math.isfinite(stiffness) and stiffness > 0.0):
            raise ValueError(f"stance stiffness factor must be finite and > 0, got "
                             f"{stiffness!r}")
        self.force_reference[index] = forces
        self.joint_control["force_tracking_gain"][index] = gains
        self.joint_control["force_stiffness"][index] = stiffness

    def stop_force_tracking(self, joints: np.ndarray | None = None) -> None:
        """Plain position control (integral back on) for ``joints`` (all by default).

        The force reference of a joint that was tracking restarts from its present force
        (the low-pass mean that pressure feedback, if configured, works about)."""
        selected = np.zeros(self.robot.joint_count, dtype=bool)
        selected[slice(None) if joints is None else joints] = True
        tracking = selected & (self.joint_control["force_tracking_gain"] > 0.0)
        self.joint_control["force_tracking_gain"][tracking] = 0.0
        self.force_reference[tracking] = self.outputs["pneumatic_force"][tracking]

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
        done, status, cylinder = advance_chunk(
            self.stepper, count, table, reference_start, self.mujoco, self.cylinders,
            self.actuators, self.controllers, self.trace, self.coupling, self.step_settings,
        )
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
        return np.column_stack([self.state["cap_pressure"], self.state["rod_pressure"]])

    def cylinder_forces(self) -> np.ndarray:
        """Net pneumatic force of each cylinder [N] (eq 4.1.11 without friction)."""
        return self.outputs["pneumatic_force"].copy()

    def atmospheric_pressure(self) -> float:
        """Atmospheric pressure [Pa] of the actuator files."""
        return float(self.params[0]["atmospheric_pressure"])
