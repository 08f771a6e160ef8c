"""The operator console: a viser server around one :class:`RobotSimulation`.

The console is a thin layer: the physics, control and kinematics live in
:mod:`pneumaquad.robot`; here a background thread steps the simulation in chunks
(20 ms of simulated time by default, optionally paced to real time), copies the state
into the 3-D scene (:mod:`.scene`) and the GUI (:mod:`.gui`), and the GUI handlers call
the public methods of :class:`ConsoleApp` (start, pause, reset, step, rebuild, supply
pressure, gain scales, teleoperation).

Replay mode (:meth:`ConsoleApp.open_run`): a run folder's model and trajectory are drawn
instead of the live robot (:mod:`.replay`), the live simulation is paused and kept; a time
slider or playback picks the sample; :meth:`ConsoleApp.back_to_live` returns. In both
modes the support polygon and the centre-of-mass projection are drawn
(:class:`.scene.StabilityOverlay`) and the static stability margin is shown.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import viser

from pneumaquad.locomotion.walking import WALKING_ANGLES
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.errors import SimulationDivergedError
from pneumaquad.robot.feedback import FootFeedback, foot_feedback
from pneumaquad.robot.scenarios import standing_height
from pneumaquad.robot.simulation import RobotSimulation

from .devices import DeviceLink, DeviceServer
from .gui import ConsoleControls
from .replay import ReplayError, ReplayRun, Stability, static_stability
from .scene import FeedbackArrows, RobotScene, StabilityOverlay
from .teleop import FootTeleoperation
from .walking import ConsoleWalking

__all__ = ["ConsoleApp", "initial_pose"]

#: Extra clearance of the feet above the ground at reset [m].
#: Simulated time [s] a free robot stands before the console shows it: it is placed 3 mm
#: above the ground and lands on its feet (all four loaded after about 0.3 s).
SETTLE_TIME = 1.0
_DROP_CLEARANCE = 0.003


def initial_pose(simulation: RobotSimulation) -> np.ndarray:
    """Put ``simulation`` in the console's reset pose; return its joint angles [rad].

    Every leg at the walking angles of :mod:`pneumaquad.locomotion.walking` (the neutral
    stance of the crawl, with room to step and sway); a free robot is placed with its
    feet just above flat ground and simulated for :data:`SETTLE_TIME` so that it starts
    standing on its feet (the clock then starts from 0, and the air counter of a regulated
    supply too); all joints closed-loop at that pose.
    """
    robot = simulation.robot
    angles = np.tile(WALKING_ANGLES, len(robot.legs))
    if robot.free:
        height = standing_height(simulation, WALKING_ANGLES) + _DROP_CLEARANCE
        simulation.set_pose(angles, thorax_position=np.array([0.0, 0.0, height]))
    else:
        simulation.set_pose(angles)
    simulation.command_angles(angles)
    if robot.free:
        simulation.step(round(SETTLE_TIME / simulation.control_step))
        simulation.restart_clock()  # the console's clock starts with the robot standing
    return angles


class ConsoleApp:
    """Browser console: live 3-D robot, run controls, pneumatics, teleoperation, plots.

    Parameters
    ----------
    params : str
        Robot parameter set name or TOML path.
    configuration : {"quadruped", "fixed", "testbed"}
    environment : {"flat", "block", "ramp", "rough"}
    host : str
        Interface to bind; loopback by default (the console has no authentication).
    port : int
        TCP port; 0 picks a free one (see :attr:`port`).
    overrides : sequence of str
        ``--set``-style parameter overrides.
    chunk : float
        Simulated time per chunk [s] between scene/GUI updates.
    real_time : bool
        Pace the simulation to the wall clock (else run as fast as it goes).
    device_port : int, optional
        UDP port for external input devices (:mod:`.devices`) on ``host``; 0 picks a
        free one (see ``app.devices.server.port``); None: no device port.
    """

    def __init__(self, params: str = "crr-quadruped", configuration: str = "quadruped",
                 environment: str = "flat", host: str = "127.0.0.1", port: int = 8080,
                 overrides: Sequence[str] = (), chunk: float = 0.02,
                 real_time: bool = True, device_port: int | None = None) -> None:
        self.params = params
        self.overrides = list(overrides)
        self.chunk = chunk
        self.real_time = real_time
        self.running = False
        self.message = ""
        self._last_good: dict[str, object] | None = None  # snapshot before each chunk
        self.lock = threading.RLock()
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server.scene.set_up_direction("+z")
        # from the robot's right and behind, aimed past it, so that the robot sits left of
        # the control panel and the block ahead of it (environment.block_position) shows
        self.server.initial_camera.position = (-0.4, -2.0, 1.2)
        self.server.initial_camera.look_at = (0.7, 0.0, 0.15)
        self.scene: RobotScene | None = None
        self.teleop: FootTeleoperation | None = None
        self.replay: ReplayRun | None = None
        self.replay_scene: RobotScene | None = None
        self.replay_time = 0.0
        self.replay_playing = False
        self.stability = Stability()
        self.overlay = StabilityOverlay(self.server)
        self.feedback_arrows = FeedbackArrows(self.server)
        self.feedback: FootFeedback | None = None
        self.devices: DeviceLink | None = None
        if device_port is not None:
            self.devices = DeviceLink(DeviceServer(host, device_port))
        self._build(configuration, environment)
        self.controls = ConsoleControls(self)
        self.refresh()
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="console-sim", daemon=True)
        self._thread.start()

    # --- model -----------------------------------------------------------------------
    def _build(self, configuration: str, environment: str) -> None:
        parameters = load_robot(self.params, self.overrides)
        robot = build_robot(parameters, configuration, environment)
        simulation = RobotSimulation(robot)
        if self.scene is not None:
            self.scene.remove()
        if self.teleop is not None:
            self.teleop.remove()
        self.configuration, self.environment = configuration, environment
        self.simulation = simulation
        self.home_angles = initial_pose(simulation)
        self.initial_supply = simulation.supply_pressure()  # tank or regulated [Pa]
        self.base_gain_scale = simulation.bank.base_gain_scale.copy()
        self.chunk_steps = max(1, round(self.chunk / simulation.control_step))
        self.scene = RobotScene(self.server, robot)
        self.teleop = FootTeleoperation(self.server, simulation, self.home_angles,
                                        lock=self.lock)
        self.walking = ConsoleWalking(simulation)

    def rebuild(self, configuration: str, environment: str) -> None:
        """Build a new model (configuration/environment), keeping supply and gain settings."""
        with self.lock:
            self.running = False
            self._leave_replay()
            supply = self.supply_gauge_pressure()
            scales = {t: self.gain_scale_of(t) for t in ("alpha", "beta", "gamma")}
            self._build(configuration, environment)
            self.set_supply_pressure(supply)
            for joint_type, scale in scales.items():
                self.set_gain_scale(joint_type, scale)
            self.controls.clear_history()
            self.refresh()

    # --- run control -----------------------------------------------------------------
    @property
    def port(self) -> int:
        """The TCP port the server listens on."""
        return int(self.server.get_port())

    @property
    def host(self) -> str:
        """The interface the server is bound to."""
        return str(self.server.get_host())

    def start(self) -> None:
        """Run the simulation continuously (leaving replay mode)."""
        if self.replay is not None:
            self.back_to_live()
        self.running = True
        self.message = ""
        self._wake.set()

    def pause(self) -> None:
        """Stop stepping (the state is kept)."""
        self.running = False
        self.refresh()

    def step_once(self) -> None:
        """Advance one chunk (paused or not; leaves replay mode)."""
        if self.replay is not None:
            self.back_to_live()
        self.advance()

    def reset(self) -> None:
        """Back to the reset pose, time 0, air counter 0; styluses back home."""
        with self.lock:
            self.running = False
            self._leave_replay()
            self.home_angles = initial_pose(self.simulation)
            self.teleop.reset()
            if self.devices is not None:
                self.devices.clear_placements()
            self.walking = ConsoleWalking(self.simulation)
            self.teleop.enabled = True
            self.controls.clear_history()
            self.refresh()

    def advance(self, steps: int | None = None) -> None:
        """Advance ``steps`` control steps (one chunk by default) and refresh the views."""
        with self.lock:
            if self.devices is not None:
                self.devices.apply_inputs(self.teleop, self.simulation.robot.legs)
            count = self.chunk_steps if steps is None else steps
            if self.walking.mode == "shared":
                placed = self.devices.placed if self.devices is not None else {}
                # a foot placed with its device's button stays where it was placed; the
                # others follow their styluses
                self.walking.place_front_feet({leg: state.target
                                               for leg, state in self.teleop.legs.items()
                                               if leg not in placed})
                if self.devices is not None:
                    self.walking.place_front_feet(self.devices.take_placements())
            self._last_good = self.simulation.snapshot(self._last_good)
            try:
                self.walking.step(count)
            except SimulationDivergedError as error:
                # the safe state: paused at the last good state, the divergence shown
                self.simulation.restore(self._last_good)
                self.running = False
                self.message = (f"{error} — paused at the last good state, t = "
                                f"{self.simulation.time:.3f} s (divergences so far: "
                                f"{self.simulation.divergences}); Reset to start again")
            self.refresh()
            if self.devices is not None and self.feedback is not None:
                self.devices.send_feedback(self.simulation, self.teleop, self.feedback)

    def set_walking(self, mode: str | None = None, speed: float | None = None,
                    heading: float | None = None, yaw_rate: float | None = None) -> None:
        """Walking mode (off, automatic, shared), body speed [m/s], heading [rad] and yaw
        rate [rad/s] (automatic mode).

        A walking mode takes all twelve joints (the styluses then only choose the front
        footholds, in shared mode); ``off`` hands the front legs back to the styluses.
        """
        with self.lock:
            # the command first: a mode that begins walking begins with it
            if speed is not None or heading is not None or yaw_rate is not None:
                self.walking.command(self.walking.speed if speed is None else speed,
                                     self.walking.heading if heading is None else heading,
                                     yaw_rate)
            if mode is not None:
                self.walking.set_mode(mode)
                self.teleop.enabled = self.walking.mode == "off"
                if self.teleop.enabled:
                    self.teleop.apply_all()
            self.controls.update()

    def refresh(self) -> None:
        """Copy the simulation (or the replayed sample) state into the scene and the GUI."""
        with self.lock:
            if self.replay is not None:
                self._show_replay()
                return
            data = self.simulation.data
            self.scene.update(data)
            thorax = self.simulation.robot.thorax_id
            self.teleop.follow_thorax(data.xpos[thorax].copy(), data.xquat[thorax].copy())
            self.feedback = foot_feedback(self.simulation)
            self.feedback_arrows.update(self.simulation, self.feedback, list(self.teleop.legs))
            self.stability = static_stability(self.simulation)
            self.overlay.update(self.stability)
            self.controls.update()

    # --- replay ----------------------------------------------------------------------
    @property
    def replaying(self) -> bool:
        """True in replay mode."""
        return self.replay is not None

    def open_run(self, folder: str | Path) -> bool:
        """Replay the run folder ``folder``; False (and a message) when it cannot be read.

        The live simulation is paused and hidden (its state is kept); the replayed robot
        is drawn from the folder's ``model.xml`` at its first trajectory sample.
        """
        with self.lock:
            try:
                replay = ReplayRun(folder)
            except ReplayError as error:
                self.message = str(error)
                self.controls.show_error(self.message)
                self.refresh()
                return False
            self.running = False
            self._leave_replay()
            self.message = ""
            self.replay = replay
            self.replay_scene = RobotScene(self.server, replay, root="/replay")
            self.scene.set_visible(False)
            self.teleop.thorax_frame.visible = False
            self.replay_time = float(replay.times[0])
            self.controls.enter_replay(replay)
            self.refresh()
            return True

    def set_replay_time(self, time_s: float) -> None:
        """Show the replayed sample nearest ``time_s`` [s] (no-op outside replay mode)."""
        with self.lock:
            if self.replay is None:
                return
            self.replay_time = float(np.clip(time_s, self.replay.times[0], self.replay.duration))
            self._show_replay()

    def play_replay(self, playing: bool = True) -> None:
        """Play the replay at real speed from the slider's time (or pause it)."""
        self.replay_playing = bool(playing) and self.replay is not None
        if self.replay_playing and self.replay_time >= self.replay.duration:
            self.set_replay_time(float(self.replay.times[0]))
        self._wake.set()

    def back_to_live(self) -> None:
        """Leave replay mode: the live robot (paused, as it was) is shown again."""
        with self.lock:
            self._leave_replay()
            self.refresh()

    def _leave_replay(self) -> None:
        self.replay_playing = False
        if self.replay is None:
            return
        self.replay = None
        if self.replay_scene is not None:
            self.replay_scene.remove()
            self.replay_scene = None
        self.scene.set_visible(True)
        self.teleop.thorax_frame.visible = True
        self.controls.leave_replay()

    def _show_replay(self) -> None:
        replay = self.replay
        index = replay.show(self.replay_time)
        row = replay.row_at(self.replay_time)
        self.replay_scene.update(replay.data)
        self.feedback_arrows.hide()
        self.stability = replay.stability(row)
        self.overlay.update(self.stability)
        self.controls.update_replay(replay, index, row)

    def _loop(self) -> None:
        wall_start, sim_start = time.perf_counter(), self.simulation.time
        while not self._stop.is_set():
            if self.replay_playing:
                self._play_step()
                continue
            if not self.running:
                self._wake.wait(0.05)
                self._wake.clear()
                wall_start, sim_start = time.perf_counter(), self.simulation.time
                continue
            self.advance()
            if self.real_time:
                ahead = (self.simulation.time - sim_start) - (time.perf_counter() - wall_start)
                if ahead > 0:
                    time.sleep(ahead)
                elif ahead < -0.5:  # fell behind: do not try to catch up
                    wall_start, sim_start = time.perf_counter(), self.simulation.time

    def _play_step(self, period: float = 0.05) -> None:
        started = time.perf_counter()
        time.sleep(period)
        with self.lock:
            if self.replay is None or not self.replay_playing:
                return
            self.set_replay_time(self.replay_time + time.perf_counter() - started)
            if self.replay_time >= self.replay.duration:
                self.replay_playing = False
                self.controls.update_replay(self.replay, self.replay.index_at(self.replay_time),
                                            self.replay.row_at(self.replay_time))

    def close(self) -> None:
        """Stop the simulation thread and the server."""
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout=5.0)
        if self.devices is not None:
            self.devices.close()
        self.server.stop()

    # --- pneumatics and control ------------------------------------------------------
    def supply_gauge_pressure(self) -> float:
        """Regulated supply pressure [Pa, gauge] of the cylinders."""
        actuator = self.simulation.bank.actuators[0]
        return float(actuator.supply.supply_pressure - actuator.gas.atmospheric_pressure)

    def set_supply_pressure(self, gauge_pressure: float) -> None:
        """Set the regulated supply pressure [Pa, gauge] of every cylinder, live.

        Goes through the actuator bank's setter: the cylinders' validated parameters and
        their packed records change together.

        Raises
        ------
        ParameterError
            The absolute pressure is outside ``supply.supply_pressure``'s range (at most
            100 MPa, above the exhaust pressure, at most a tank's initial pressure);
            nothing changes.
        """
        with self.lock:
            bank = self.simulation.bank
            bank.set_supply_pressure(bank.params["atmospheric_pressure"] + gauge_pressure)

    def gain_scale_of(self, joint_type: str) -> float:
        """Operator gain scale of ``joint_type`` (1 = the parameter file's gains)."""
        simulation = self.simulation
        index = simulation.robot.joint_types.index(joint_type)
        return float(simulation.bank.base_gain_scale[index] / self.base_gain_scale[index])

    def set_gain_scale(self, joint_type: str, scale: float) -> None:
        """Scale Kp, Ki, Kd of every ``joint_type`` controller by ``scale``, live (through
        the actuator bank: the controller tables' ``gain_scale`` becomes the file's
        times ``scale``).

        Raises
        ------
        ParameterError
            The resulting gain scale is outside [0, 100].
        """
        with self.lock:
            simulation = self.simulation
            mask = np.array([t == joint_type for t in simulation.robot.joint_types])
            simulation.bank.set_gain_scale(self.base_gain_scale[mask] * scale, mask)

    def set_mapping(self, scale: float | None = None,
                    shift: Sequence[float] | None = None, enabled: bool | None = None) -> None:
        """Change the stylus-to-foot mapping (scale, offset shift [m]) or enable it."""
        with self.lock:
            if scale is not None:
                self.teleop.scale = float(scale)
            if shift is not None:
                self.teleop.shift = np.asarray(shift, dtype=float)
            if enabled is not None:
                self.teleop.enabled = bool(enabled)
                if not enabled:
                    self.simulation.command_angles(self.home_angles)
            self.teleop.apply_all()
