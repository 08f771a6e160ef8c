"""GUI panel of the operator console: run controls, model, pneumatics, teleoperation, plots.

Each control's handler calls one public method of :class:`pneumaquad.console.app.ConsoleApp`;
:meth:`ConsoleControls.update` refreshes the readouts and plots after every chunk.
"""

from __future__ import annotations

import time
from collections import deque
from typing import TYPE_CHECKING

import numpy as np
import viser
import viser.uplot as uplot

from pneumaquad.robot.builder import CONFIGURATIONS
from pneumaquad.robot.environment import ENVIRONMENTS

if TYPE_CHECKING:
    from .app import ConsoleApp

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
        self._last_plot = 0.0
        with gui.add_folder("Simulation"):
            self.start_button = gui.add_button("Start", icon=viser.Icon.PLAYER_PLAY)
            self.pause_button = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE)
            self.step_button = gui.add_button("Step 20 ms", icon=viser.Icon.PLAYER_SKIP_FORWARD)
            self.reset_button = gui.add_button("Reset", icon=viser.Icon.REFRESH)
            self.real_time = gui.add_checkbox("Real time", app.real_time)
            self.status = gui.add_markdown("")
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
        self.real_time.on_update(lambda _event: setattr(app, "real_time", self.real_time.value))
        self.configuration.on_update(lambda _event: self._rebuild())
        self.environment.on_update(lambda _event: self._rebuild())
        self.supply.on_update(lambda _event: app.set_supply_pressure(1000.0 * self.supply.value))
        for joint_type, slider in self.gains.items():
            slider.on_update(
                lambda _event, t=joint_type, s=slider: app.set_gain_scale(t, s.value))
        self.teleop_enabled.on_update(
            lambda _event: app.set_mapping(enabled=self.teleop_enabled.value))
        self.scale.on_update(lambda _event: app.set_mapping(scale=self.scale.value))
        self.shift.on_update(lambda _event: app.set_mapping(shift=self.shift.value))

    def _rebuild(self) -> None:
        if (self.configuration.value, self.environment.value) != (
            self.app.configuration, self.app.environment
        ):
            self.app.rebuild(self.configuration.value, self.environment.value)

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
