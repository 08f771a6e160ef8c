"""GUI panel of the operator console: run controls, model, pneumatics, teleoperation, plots.

Each control's handler calls one public method of :class:`pneumaquad.console.app.ConsoleApp`;
:meth:`ConsoleControls.update` refreshes the readouts and plots after every chunk.
"""

from __future__ import annotations

import math
import time
from collections import deque
from typing import TYPE_CHECKING

import numpy as np
import viser
import viser.uplot as uplot

from pneumaquad.params import ParameterError
from pneumaquad.robot.builder import CONFIGURATIONS
from pneumaquad.robot.environment import ENVIRONMENTS

from .devices import feedback_status
from .walking import MAX_SPEED, MAX_YAW_RATE, WALKING_MODES

if TYPE_CHECKING:
    from .app import ConsoleApp
    from .replay import ReplayRun

__all__ = ["PLOTTED_LEG", "ConsoleControls"]

#: The leg whose joints are plotted.
PLOTTED_LEG = "front_right"
#: Seconds of simulated time shown in the plots.
PLOT_WINDOW = 10.0
#: Minimum wall time between plot updates sent to the browser [s].
PLOT_PERIOD = 0.1
_JOINT_COLOURS = {"alpha": "#d62728", "beta": "#1f77b4", "gamma": "#2ca02c"}
_NORMAL_LITRE_DENSITY = 1.2041e-3  # kg per normal litre (20 °C, 1 atm)


def _series(label: str, colour: str, dash: bool = False) -> uplot.Series:
    series = uplot.Series(label=label, stroke=colour, width=1.5)
    if dash:
        series["dash"] = [6, 4]
    return series


class ConsoleControls:
    """The console's GUI panel, bound to a :class:`ConsoleApp`.

    Parameters
    ----------
    app : ConsoleApp
    """

    def __init__(self, app: ConsoleApp) -> None:
        self.app = app
        gui = app.server.gui
        self.history: deque[np.ndarray] = deque()
        self._syncing = False
        self._last_plot = 0.0
        with gui.add_folder("Simulation"):
            self.start_button = gui.add_button("Start", icon=viser.Icon.PLAYER_PLAY)
            self.pause_button = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE)
            self.step_button = gui.add_button("Step 20 ms", icon=viser.Icon.PLAYER_SKIP_FORWARD)
            self.reset_button = gui.add_button("Reset", icon=viser.Icon.REFRESH)
            self.real_time = gui.add_checkbox("Real time", app.real_time)
            self.status = gui.add_markdown("")
        with gui.add_folder("Replay"):
            self.run_folder = gui.add_text("Run folder", "")
            self.open_button = gui.add_button("Open run", icon=viser.Icon.FOLDER_OPEN)
            self.replay_slider = gui.add_slider("Replay time [s]", 0.0, 1.0, 0.01, 0.0,
                                                disabled=True)
            self.play_button = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY,
                                              disabled=True)
            self.replay_pause_button = gui.add_button("Pause replay",
                                                      icon=viser.Icon.PLAYER_PAUSE,
                                                      disabled=True)
            self.live_button = gui.add_button("Back to live", icon=viser.Icon.ARROW_BACK,
                                              disabled=True)
            self.replay_status = gui.add_markdown("")
        with gui.add_folder("Stability"):
            self.stability = gui.add_markdown("")
        with gui.add_folder("Walking"):
            self.walk_mode = gui.add_dropdown("Walking mode", WALKING_MODES,
                                              initial_value="off")
            self.walk_speed = gui.add_slider("Speed [mm/s]", -1000 * MAX_SPEED,
                                             1000 * MAX_SPEED, 5.0, 0.0)
            self.walk_heading = gui.add_slider("Heading [deg]", -180.0, 180.0, 5.0, 0.0)
            fastest_turn = math.degrees(MAX_YAW_RATE)
            self.walk_yaw_rate = gui.add_slider("Yaw rate [deg/s]", -fastest_turn,
                                                fastest_turn, 0.5, 0.0)
            self.walk_stop = gui.add_button("Stop walking", icon=viser.Icon.PLAYER_STOP)
            self.walk_status = gui.add_markdown("")
        with gui.add_folder("Model"):
            self.configuration = gui.add_dropdown("Configuration", CONFIGURATIONS,
                                                  initial_value=app.configuration)
            self.environment = gui.add_dropdown("Environment", ENVIRONMENTS,
                                                initial_value=app.environment)
        with gui.add_folder("Pneumatics"):
            self.supply = gui.add_slider("Supply [kPa g]", 100.0, 800.0, 10.0,
                                         round(app.supply_gauge_pressure() / 1000.0))
            self.gains = {
                joint_type: gui.add_slider(f"Gain scale {joint_type}", 0.0, 3.0, 0.05, 1.0)
                for joint_type in ("alpha", "beta", "gamma")
            }
            self.supply_gauge = gui.add_progress_bar(100.0, color="blue")
            self.readout = gui.add_markdown("")
        with gui.add_folder("Teleoperation"):
            self.teleop_enabled = gui.add_checkbox("Styluses drive front feet", True)
            self.scale = gui.add_slider("Scale", 0.2, 3.0, 0.1, 1.0)
            self.shift = gui.add_vector3("Offset shift [m]", (0.0, 0.0, 0.0), step=0.01)
            self.teleop_status = gui.add_markdown("")
            self.feedback_readout = gui.add_markdown("")
        with gui.add_folder(f"Plots ({PLOTTED_LEG})"):
            empty = tuple(np.zeros(1) for _ in range(7))
            angle_series = [uplot.Series(label="t [s]")]
            pressure_series = [uplot.Series(label="t [s]")]
            for joint_type, colour in _JOINT_COLOURS.items():
                angle_series += [_series(f"{joint_type} ref", colour, dash=True),
                                 _series(f"{joint_type}", colour)]
                pressure_series += [_series(f"{joint_type} cap", colour),
                                    _series(f"{joint_type} rod", colour, dash=True)]
            scales = {"x": uplot.Scale(time=False, auto=True)}
            self.angle_plot = gui.add_uplot(empty, tuple(angle_series), title="Joint angle [deg]",
                                            scales=scales, aspect=1.4)
            self.pressure_plot = gui.add_uplot(empty, tuple(pressure_series),
                                               title="Chamber pressure [kPa abs]",
                                               scales=scales, aspect=1.4)
        self._connect()

    def _connect(self) -> None:
        app = self.app
        self.start_button.on_click(lambda _event: app.start())
        self.pause_button.on_click(lambda _event: app.pause())
        self.step_button.on_click(lambda _event: app.step_once())
        self.reset_button.on_click(lambda _event: app.reset())
        self.open_button.on_click(lambda _event: app.open_run(self.run_folder.value.strip()))
        self.replay_slider.on_update(lambda _event: self._slide())
        self.play_button.on_click(lambda _event: app.play_replay(True))
        self.replay_pause_button.on_click(lambda _event: app.play_replay(False))
        self.live_button.on_click(lambda _event: app.back_to_live())
        self.real_time.on_update(lambda _event: setattr(app, "real_time", self.real_time.value))
        self.configuration.on_update(lambda _event: self._rebuild())
        self.environment.on_update(lambda _event: self._rebuild())
        self.supply.on_update(lambda _event: self._set_supply())
        for joint_type, slider in self.gains.items():
            slider.on_update(
                lambda _event, t=joint_type, s=slider: app.set_gain_scale(t, s.value))
        self.teleop_enabled.on_update(
            lambda _event: app.set_mapping(enabled=self.teleop_enabled.value))
        self.scale.on_update(lambda _event: app.set_mapping(scale=self.scale.value))
        self.shift.on_update(lambda _event: app.set_mapping(shift=self.shift.value))
        self.walk_mode.on_update(lambda _event: self._walk())
        self.walk_speed.on_update(lambda _event: self._walk())
        self.walk_heading.on_update(lambda _event: self._walk())
        self.walk_yaw_rate.on_update(lambda _event: self._walk())
        self.walk_stop.on_click(lambda _event: self._stop_walking())

    def _walk(self) -> None:
        if self._syncing:
            return
        self.app.set_walking(self.walk_mode.value, self.walk_speed.value / 1000.0,
                             math.radians(self.walk_heading.value),
                             math.radians(self.walk_yaw_rate.value))

    def _stop_walking(self) -> None:
        self._syncing = True
        try:
            self.walk_speed.value = 0.0
            self.walk_yaw_rate.value = 0.0
        finally:
            self._syncing = False
        self.app.set_walking(speed=0.0, yaw_rate=0.0)

    def show_walking_command(self) -> None:
        """Move the walking widgets to the app's present command (set from elsewhere)."""
        walking = self.app.walking
        self._syncing = True
        try:
            self.walk_mode.value = walking.mode
            self.walk_speed.value = round(1000.0 * walking.speed)
            self.walk_heading.value = round(math.degrees(walking.heading))
            self.walk_yaw_rate.value = round(math.degrees(walking.yaw_rate), 1)
        finally:
            self._syncing = False

    def _set_supply(self) -> None:
        """The supply slider [kPa g]: a value the parameters refuse leaves the supply as it
        was and shows why."""
        try:
            self.app.set_supply_pressure(1000.0 * self.supply.value)
        except ParameterError as error:
            self.app.message = "supply unchanged: " + "; ".join(map(str, error.problems))
            self.app.refresh()

    def _rebuild(self) -> None:
        if (self.configuration.value, self.environment.value) != (
            self.app.configuration, self.app.environment
        ):
            self.app.rebuild(self.configuration.value, self.environment.value)

    def _slide(self) -> None:
        if not self._syncing:
            self.app.set_replay_time(float(self.replay_slider.value))

    # --- replay ----------------------------------------------------------------------
    def show_error(self, message: str) -> None:
        """Show ``message`` under the replay controls (e.g. a folder that is no run)."""
        self.replay_status.content = f"⚠ {message}"

    def enter_replay(self, replay: ReplayRun) -> None:
        """Set the slider to the run's time range and enable the replay buttons."""
        times = replay.times
        step = float(np.median(np.diff(times))) if len(times) > 1 else 0.01
        self._syncing = True
        try:
            self.replay_slider.max = max(float(times[-1]), float(times[0]) + step)
            self.replay_slider.min = float(times[0])
            self.replay_slider.step = step
            self.replay_slider.value = float(times[0])
        finally:
            self._syncing = False
        for handle in (self.replay_slider, self.play_button, self.replay_pause_button,
                       self.live_button):
            handle.disabled = False
        self.run_folder.value = str(replay.folder)
        self.clear_history()

    def leave_replay(self) -> None:
        """Disable the replay controls (back to live)."""
        for handle in (self.replay_slider, self.play_button, self.replay_pause_button,
                       self.live_button):
            handle.disabled = True
        self.replay_status.content = ""
        self.clear_history()

    def update_replay(self, replay: ReplayRun, index: int, row: int | None) -> None:
        """Readouts, gauge and plots of the replayed sample ``index``, recording ``row``."""
        app = self.app
        time_s = float(replay.times[index])
        if abs(float(self.replay_slider.value) - app.replay_time) > 1e-9:
            self._syncing = True
            try:
                self.replay_slider.value = app.replay_time
            finally:
                self._syncing = False
        state = "playing" if app.replay_playing else "paused"
        self.status.content = (f"**replay** ({state}) of `{replay.folder.name}`: "
                               f"t = {time_s:.2f} s, sample {index} of {len(replay.times) - 1}")
        self.replay_status.content = f"Replaying `{replay.folder}`, {replay.duration:.2f} s"
        self.teleop_status.content = "(replay: teleoperation off)"
        self.feedback_readout.content = ""
        self._show_stability()
        if row is None:
            self.readout.content = "No recording (recording.parquet) in this run folder."
            return
        supply = replay.value("supply pressure [Pa]", row)
        initial = replay.value("supply pressure [Pa]", 0)
        if np.isfinite(supply) and initial > 0:
            self.supply_gauge.value = float(np.clip(100.0 * supply / initial, 0.0, 100.0))
        air = replay.value("air consumed [kg]", row)
        normal_litres = replay.value("air consumed [NL]", row)
        forces = [replay.value(f"{leg} foot normal force [N]", row) for leg in replay.legs]
        self.readout.content = (
            f"Supply {supply / 1000.0:.0f} kPa abs (recorded; gauge: share of the first "
            f"sample)  \n"
            f"Air consumed {1000.0 * air:.3f} g = {normal_litres:.2f} NL  \n"
            f"Foot forces [N]: {', '.join(f'{f:.0f}' for f in forces)}  \n"
            f"Contacts: {app.replay_scene.contact_count}"
        )
        record = replay.recording
        names = [f"{PLOTTED_LEG}_{joint_type}" for joint_type in _JOINT_COLOURS]
        columns = [f"{n} {kind}" for n in names for kind in ("reference [rad]", "angle [rad]")]
        pressures = [f"{n} {kind}" for n in names
                     for kind in ("cap pressure [Pa]", "rod pressure [Pa]")]
        if not all(c in record for c in columns + pressures):
            return
        times = replay.record_times
        window = slice(int(np.searchsorted(times, times[row] - PLOT_WINDOW)), row + 1)
        self.angle_plot.data = (times[window], *(np.degrees(record[c][window]) for c in columns))
        self.pressure_plot.data = (times[window],
                                   *(record[c][window] / 1000.0 for c in pressures))

    def _show_stability(self) -> None:
        stability = self.app.stability
        margin = stability.margin
        feet = len(stability.polygon)
        source = "recorded" if self.app.replaying else "live"
        if np.isfinite(margin):
            verdict = "stable" if margin >= 0.0 else "**outside the support polygon**"
            text = f"Stability margin {1000.0 * margin:.0f} mm ({verdict}; {source})"
        else:
            text = f"Stability margin: n/a ({source})"
        self.stability.content = (f"{text}  \nSupport polygon: {feet} vertices; centre of "
                                  f"mass at ({stability.com[0]:.3f}, {stability.com[1]:.3f}) m")

    def clear_history(self) -> None:
        """Forget the plotted samples (after a reset or a rebuild)."""
        self.history.clear()
        self._last_plot = 0.0

    def _joints(self) -> np.ndarray | None:
        names = self.app.simulation.robot.joint_names
        if f"{PLOTTED_LEG}_alpha" not in names:
            return None
        first = names.index(f"{PLOTTED_LEG}_alpha")
        return np.arange(first, first + 3)

    def update(self) -> None:
        """Refresh readouts, gauges and (at most every :data:`PLOT_PERIOD`) the plots."""
        app = self.app
        simulation = app.simulation
        state = "running" if app.running else "paused"
        lines = [f"t = {simulation.time:.2f} s, **{state}**, {app.configuration} / "
                 f"{app.environment}"]
        if app.message:
            lines.append(f"⚠ {app.message}")
        self.status.content = "  \n".join(lines)
        supply = simulation.supply_pressure() - simulation.atmospheric_pressure()
        initial = app.initial_supply - simulation.atmospheric_pressure()
        self.supply_gauge.value = float(np.clip(100.0 * supply / initial, 0.0, 100.0))
        air = simulation.air_consumed()
        forces = simulation.foot_normal_forces()
        self.readout.content = (
            f"Supply {supply / 1000.0:.0f} kPa g (gauge: share of the initial "
            f"{initial / 1000.0:.0f} kPa)  \n"
            f"Air consumed {1000.0 * air:.3f} g = {air / _NORMAL_LITRE_DENSITY:.2f} NL  \n"
            f"Foot forces [N]: {', '.join(f'{f:.0f}' for f in forces)}  \n"
            f"Contacts: {app.scene.contact_count}"
        )
        self.teleop_status.content = app.teleop.status()
        self.walk_status.content = app.walking.status()
        if app.feedback is not None:
            self.feedback_readout.content = feedback_status(
                simulation, app.feedback, list(app.teleop.legs), app.devices)
        self._show_stability()
        joints = self._joints()
        if joints is None:
            return
        pressures = simulation.chamber_pressures()[joints] / 1000.0
        sample = np.concatenate([
            [simulation.time],
            np.degrees(np.column_stack([simulation.reference_angles[joints],
                                        simulation.joint_angles()[joints]]).ravel()),
            pressures.ravel(),
        ])
        self.history.append(sample)
        while self.history and sample[0] - self.history[0][0] > PLOT_WINDOW:
            self.history.popleft()
        now = time.perf_counter()
        if now - self._last_plot >= PLOT_PERIOD or not app.running:
            self._last_plot = now
            table = np.array(self.history)
            self.angle_plot.data = tuple(table[:, k] for k in range(7))
            self.pressure_plot.data = (table[:, 0], *(table[:, 7 + k] for k in range(6)))
