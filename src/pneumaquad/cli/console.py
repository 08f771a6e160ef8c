"""``pneumaquad console``: start the operator console in the browser.

Register with ``app.command("console")(console_command)`` in :mod:`pneumaquad.cli.main`.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from pneumaquad.cli.common import (
    WALL_DURATION,
    AllowRemoteOption,
    SetOption,
    check_bind,
    console,
    option_range,
    stderr_console,
)
from pneumaquad.io.interruption import deferred_interrupt
from pneumaquad.params.fields import Bounds

__all__ = ["console_command", "serve_console"]

_PORT_RANGE = Bounds(0, 65535, lower_inclusive=True)


def serve_console(params: str = "crr-quadruped", configuration: str = "quadruped",
                  environment: str = "flat", host: str = "127.0.0.1", port: int = 8080,
                  duration: float | None = None, overrides: list[str] | None = None,
                  start: bool = False, replay: Path | None = None,
                  device_port: int | None = None) -> None:
    """Run the console until Ctrl-C (or for ``duration`` wall seconds), then stop cleanly.

    Parameters
    ----------
    params, configuration, environment, host, port, overrides
        See :class:`pneumaquad.console.app.ConsoleApp`.
    duration : float, optional
        Wall-clock seconds to serve before stopping (tests, demos); forever by default.
    start : bool
        Start the simulation immediately instead of paused.
    replay : Path, optional
        A run folder to open in replay mode at once (see :meth:`ConsoleApp.open_run`).
    device_port : int, optional
        UDP port for external input devices on ``host`` (0: any free port); none by default.
    """
    from pneumaquad.console.app import ConsoleApp
    from pneumaquad.console.keyboard import HELP, KeyboardControl

    app = ConsoleApp(params, configuration, environment, host=host, port=port,
                     overrides=overrides or [], device_port=device_port)
    shown = "localhost" if app.host in ("127.0.0.1", "::1") else app.host
    console.print(f"Operator console on http://{shown}:{app.port} (Ctrl-C stops)")
    if app.devices is not None:
        server = app.devices.server
        console.print(f"Input devices: UDP {server.host}:{server.port}")
    if app.host not in ("127.0.0.1", "::1", "localhost"):
        stderr_console.print(f"[yellow]warning:[/] bound to {app.host}: anyone who can reach this "
                             "port can drive the simulation (no authentication)")
    if replay is not None:
        if app.open_run(replay):
            console.print(f"Replaying {replay}")
        else:
            stderr_console.print(f"[yellow]warning:[/] {app.message}")
    elif start:
        app.start()
    keyboard = KeyboardControl(
        lambda: (app.walking.mode, app.walking.speed, app.walking.heading,
                 app.walking.yaw_rate),
        lambda mode, speed, heading, yaw_rate: (app.set_walking(mode, speed, heading, yaw_rate),
                                                app.controls.show_walking_command()))
    if keyboard.active:
        console.print(HELP)
    deadline = None if duration is None else time.monotonic() + duration
    try:
        with deferred_interrupt() as stop:
            while not stop.requested and (deadline is None or time.monotonic() < deadline):
                time.sleep(0.1)
    except KeyboardInterrupt:  # a second Ctrl-C
        pass
    finally:
        keyboard.close()
        app.close()
    console.print("Console stopped.")


def console_command(
    params: Annotated[
        str, typer.Option("--params", "-p", help="Robot parameter set name or TOML path.")
    ] = "crr-quadruped",
    configuration: Annotated[
        str, typer.Option("--configuration", "-c", help="quadruped, fixed or testbed.")
    ] = "quadruped",
    environment: Annotated[
        str, typer.Option("--environment", "-e", help="flat, block, ramp or rough.")
    ] = "flat",
    host: Annotated[
        str, typer.Option(help="Interface to bind (loopback by default; no authentication).")
    ] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="TCP port (0: any free port).",
                                      callback=option_range(_PORT_RANGE))] = 8080,
    duration: Annotated[
        float | None, typer.Option(help="Stop after this many wall-clock seconds (up to "
                                   "86400).", callback=option_range(WALL_DURATION))
    ] = None,
    start: Annotated[bool, typer.Option("--start/--paused", help="Run at once.")] = False,
    overrides: SetOption = None,
    replay: Annotated[
        Path | None, typer.Option("--replay", help="Open this run folder in replay mode.")
    ] = None,
    device_port: Annotated[
        int | None,
        typer.Option("--device-port", help="UDP port for external input devices (0: any).",
                     callback=option_range(_PORT_RANGE)),
    ] = None,
    allow_remote: AllowRemoteOption = False,
) -> None:
    """Operator console in the browser: live 3-D robot, run controls, teleoperation."""
    check_bind(host, allow_remote, "--host", warn=False)  # warned once bound, below
    serve_console(params, configuration, environment, host, port, duration, overrides, start,
                  replay, device_port)
