"""Command-line interface of the networked co-simulation: ``pneumaquad serve ...``.

``serve dynamics`` runs the MuJoCo robot as a UDP server (valve, force or torque
commands; lockstep or real time); ``serve actuators`` runs the cylinders, valves and
controllers against such a server (force commands, lockstep). The wire format is
``docs/protocol.md``. Both write a run folder (recording, ``packets.parquet``,
``timing.json``, ``rtt.png``, ``timeline.png``); Ctrl-C stops at the next step, keeps
the files and exits with 130.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from pneumaquad.cli.common import (
    SIMULATED_DURATION,
    WALL_DURATION,
    AllowRemoteOption,
    OutputOption,
    SetOption,
    check_bind,
    check_step_count,
    command_group,
    console,
    number_in,
    option_range,
    refuse_occupied_output,
    stderr_console,
)
from pneumaquad.params import ParameterError
from pneumaquad.params.fields import Bounds

serve_app = command_group(help="Networked co-simulation over UDP (thesis ch. 5.1-5.3).",
                          no_args_is_help=True)

ParamsOption = Annotated[
    str, typer.Option("--params", "-p", help="Robot parameter set name or TOML path.")
]
ConfigurationOption = Annotated[
    str, typer.Option(help="Robot configuration: quadruped, fixed or testbed.")
]


def _fail(message: str, status: int = 2) -> None:
    stderr_console.print("[red]error:[/red] ", end="", highlight=False)
    stderr_console.print(message, markup=False, highlight=False)
    raise typer.Exit(status)


def _robot(params: str, overrides: list[str] | None, configuration: str,
           build: bool = True):
    """The robot of ``params``: built in MuJoCo, or (``build=False``) its joints only."""
    from pneumaquad.params import load_robot
    from pneumaquad.robot.builder import CONFIGURATIONS, build_robot, robot_joints

    if configuration not in CONFIGURATIONS:
        _fail(f"--configuration {configuration!r}: expected one of {', '.join(CONFIGURATIONS)}")
    try:
        parameters = load_robot(params, overrides or [])
        return (build_robot if build else robot_joints)(parameters, configuration)
    except (ParameterError, ValueError, FileNotFoundError) as error:
        _fail(str(error))


def _address(text: str, option: str):
    from pneumaquad.network.endpoint import parse_address

    try:
        return parse_address(text)
    except ValueError as error:
        _fail(f"{option}: {error}")


def _posture(text: str, joint_count: int) -> np.ndarray:
    try:
        values = [math.radians(float(v)) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        _fail(f"--posture {text!r}: expected three angles in degrees, alpha,beta,gamma")
    return np.tile(values, joint_count // 3)


def _print(summary: dict, keys: tuple[str, ...]) -> None:
    for key in keys:
        if key in summary and summary[key] is not None:
            console.print(f"  {key}: {summary[key]:.6g}", markup=False, highlight=False)


def _print_deadline(summary: dict) -> None:
    """How many round trips missed the control step's deadline, in words (timing.json has
    the figures)."""
    late = summary.get("round trips over deadline [count]")
    total = summary.get("round trips [count]")
    deadline = summary.get("deadline [s]")
    if late is None or not total or deadline is None:
        return
    line = (f"  round trips over the {deadline * 1e3:g} ms deadline: {late} of {total} "
            f"({100.0 * late / total:.1f} %)")
    console.print(line, markup=False, highlight=False,
                  style="yellow" if late else None)


#: Longest reply or command timeout [s].
MAX_NETWORK_TIMEOUT = 60.0
PORT_RANGE = Bounds(0, 65535, lower_inclusive=True)
TIMEOUT_RANGE = Bounds(0.0, MAX_NETWORK_TIMEOUT, "s")

BusyWaitOption = Annotated[
    float,
    typer.Option(callback=option_range(Bounds(0.0, 1.0, "s", lower_inclusive=True)),
                 parser=number_in("s"), metavar="QUANTITY",
                 help="Poll this long [s] before sleeping while waiting for a datagram: "
                 "lower, steadier latency for a busier core (0 = sleep at once; at most 1)."),
]


@serve_app.command("dynamics")
@refuse_occupied_output
def serve_dynamics(
    params: ParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    configuration: ConfigurationOption = "fixed",
    command: Annotated[str, typer.Option(help="Accepted commands: valve, force or torque.")]
    = "force",
    mode: Annotated[str, typer.Option(help="lockstep (step per command) or realtime.")]
    = "lockstep",
    bind: Annotated[str, typer.Option(help="Local address to listen on.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="UDP port (0: any free one).",
                                      callback=option_range(PORT_RANGE))] = 47000,
    peer: Annotated[str | None, typer.Option(help="Accept only HOST:PORT.")] = None,
    timeout: Annotated[float, typer.Option(help="Realtime: command timeout [s], up to 60.",
                                           callback=option_range(TIMEOUT_RANGE),
                                           parser=number_in("s"), metavar="QUANTITY")] = 0.1,
    duration: Annotated[float | None, typer.Option(
        help="Wall-clock limit [s], up to 86400.", callback=option_range(WALL_DURATION),
        parser=number_in("s"), metavar="QUANTITY")
    ] = None,
    busy_wait: BusyWaitOption = 0.002,
    posture: Annotated[str, typer.Option(help="Initial alpha,beta,gamma of every leg [deg].")]
    = "0,-30,60",
    record_every: Annotated[int, typer.Option(
        help="Record every n-th control step, 1 to 1000000.",
        callback=option_range(Bounds(1, 1_000_000, lower_inclusive=True)))] = 1,
    layout: Annotated[
        str, typer.Option(help="pnqd (docs/protocol.md) or thesis (App. C.2.4: 21 doubles, "
                          "R1 torques in, lockstep).")
    ] = "pnqd",
    output: OutputOption = None,
    allow_remote: AllowRemoteOption = False,
) -> None:
    """Serve the robot's dynamics over UDP until BYE, --duration or Ctrl-C."""
    check_bind(bind, allow_remote, "--bind")
    if layout == "thesis":
        _serve_thesis(params, overrides, configuration, bind, port, peer, duration, posture,
                      output)
        return
    if layout != "pnqd":
        _fail(f"--layout {layout!r}: expected pnqd or thesis")
    from pneumaquad.io.interruption import deferred_interrupt
    from pneumaquad.io.run_folder import create_run_folder
    from pneumaquad.network.dynamics_side import COMMAND_KINDS, DynamicsSide
    from pneumaquad.network.server import MODES, DynamicsServer

    if command not in COMMAND_KINDS:
        _fail(f"--command {command!r}: expected one of {', '.join(COMMAND_KINDS)}")
    if mode not in MODES:
        _fail(f"--mode {mode!r}: expected one of {', '.join(MODES)}")
    robot = _robot(params, overrides, configuration)
    peer_address = None if peer is None else _address(peer, "--peer")
    try:
        side = DynamicsSide(robot, command)
    except ValueError as error:
        _fail(str(error))
    side.set_pose(_posture(posture, robot.joint_count))
    try:
        server = DynamicsServer(side, (bind, port), peer_address, mode, timeout, duration,
                                None, record_every, busy_wait=busy_wait)
    except OSError as error:
        _fail(f"cannot listen on {bind}:{port}: {error}")
    server.folder = create_run_folder(output, f"serve-dynamics-{mode}")
    console.print(f"dynamics ({command}, {mode}) listening on "
                  f"{server.address[0]}:{server.address[1]}; run folder {server.folder}")
    with deferred_interrupt() as request:
        summary = server.run(request)
    _print(summary, ("control steps [count]", "simulated time [s]", "wall time [s]",
                     "malformed [count]", "duplicates [count]", "reordered [count]",
                     "foreign [count]", "timeouts [count]", "refused hellos [count]",
                     "clamped commands [count]", "divergences [count]", "achieved rate [Hz]",
                     "jitter p99 [s]", "overruns [count]"))
    _end_of_server_run(summary, request.requested)


def _end_of_server_run(summary: dict, interrupted: bool) -> None:
    """Exit 130 after Ctrl-C, 1 after a run the server ended on a diverged state."""
    if interrupted:
        stderr_console.print("[yellow]interrupted: the files hold the part that ran[/yellow]")
        raise typer.Exit(130)
    if "error" in summary:
        _fail(f"{summary['error']} (the last good state was held and the run ended; the "
              "files hold the part that ran)", status=1)


def _serve_thesis(params: str, overrides: list[str] | None, configuration: str, bind: str,
                  port: int, peer: str | None, duration: float | None, posture: str,
                  output: Path | None) -> None:
    from pneumaquad.io.interruption import deferred_interrupt
    from pneumaquad.io.run_folder import create_run_folder
    from pneumaquad.network.dynamics_side import DynamicsSide
    from pneumaquad.network.thesis_server import ThesisServer

    robot = _robot(params, overrides, configuration)
    side = DynamicsSide(robot, "torque")
    side.set_pose(_posture(posture, robot.joint_count))
    peer_address = None if peer is None else _address(peer, "--peer")
    folder = create_run_folder(output, "serve-dynamics-thesis")
    try:
        server = ThesisServer(side, (bind, port), peer_address, duration=duration,
                              folder=folder)
    except OSError as error:
        _fail(f"cannot listen on {bind}:{port}: {error}")
    console.print(f"dynamics (thesis layout, R1 torques, lockstep) listening on "
                  f"{server.address[0]}:{server.address[1]}; run folder {folder}")
    with deferred_interrupt() as request:
        summary = server.run(request)
    _print(summary, tuple(key for key in summary if key.endswith("]")))
    _end_of_server_run(summary, request.requested)


@serve_app.command("actuators")
@refuse_occupied_output
def serve_actuators(
    dynamics: Annotated[str, typer.Option(help="Dynamics server HOST:PORT.")]
    = "127.0.0.1:47000",
    params: ParamsOption = "crr-quadruped",
    overrides: SetOption = None,
    configuration: ConfigurationOption = "fixed",
    experiment: Annotated[str, typer.Option(help="hold, gamma-step or gamma-sine.")]
    = "gamma-step",
    settle: Annotated[float, typer.Option(
        help="Hold before the motion [s], 0 to 3600.",
        callback=option_range(Bounds(0.0, 3600.0, "s", lower_inclusive=True)),
        parser=number_in("s"), metavar="QUANTITY")] = 0.5,
    duration: Annotated[float, typer.Option(help="Simulated time [s], up to 3600.",
                                            callback=option_range(SIMULATED_DURATION),
                                            parser=number_in("s"), metavar="QUANTITY")] = 1.0,
    reply_timeout: Annotated[float, typer.Option(
        help="Wait for a STATE before resending [s], up to 60.",
        callback=option_range(TIMEOUT_RANGE), parser=number_in("s"), metavar="QUANTITY")
    ] = 0.05,
    busy_wait: BusyWaitOption = 0.002,
    output: OutputOption = None,
) -> None:
    """Run cylinders, valves and controllers against a dynamics server (lockstep)."""
    from pneumaquad.io.interruption import deferred_interrupt
    from pneumaquad.io.run_folder import create_run_folder
    from pneumaquad.network.actuator_side import ActuatorSide
    from pneumaquad.network.client import (
        ActuatorClient,
        DynamicsDivergedError,
        NoReplyError,
        SessionMismatchError,
    )
    from pneumaquad.network.experiments import EXPERIMENTS, make_experiment

    if experiment not in EXPERIMENTS:
        _fail(f"--experiment {experiment!r}: expected one of {', '.join(EXPERIMENTS)}")
    address = _address(dynamics, "--dynamics")
    robot = _robot(params, overrides, configuration, build=False)  # no MuJoCo on this side
    try:
        side = ActuatorSide(robot)
    except ValueError as error:
        _fail(str(error))
    try:
        check_step_count(duration, side.control_step, "--duration", f"{duration:g}")
    except ParameterError as error:
        _fail(str(error))
    folder: Path = create_run_folder(output, f"serve-actuators-{experiment}")
    client = ActuatorClient(side, address, reply_timeout=reply_timeout, folder=folder,
                            busy_wait=busy_wait)
    steps = round(duration / side.control_step)
    interrupted = False
    try:
        with deferred_interrupt() as request:
            initial = client.connect()
            try:
                plan = make_experiment(experiment, robot.joint_names, initial.joint_angles,
                                       side.control_step, settle)
            except ValueError as error:
                _fail(str(error))
            summary = client.run(plan, steps, initial, request)
            interrupted = request.requested
            client.bye()
    except NoReplyError as error:
        _fail(f"{error} (is `pneumaquad serve dynamics --command force` running there?)")
    except SessionMismatchError as error:
        _fail(str(error))
    except DynamicsDivergedError as error:
        _fail(f"{error}; run folder {folder}", status=1)
    finally:
        client.close()
    console.print(f"run folder: [bold]{folder}[/bold]")
    _print(summary, ("control steps [count]", "wall time [s]", "resends [count]",
                     "round-trip time median [s]", "round-trip time p99 [s]"))
    _print_deadline(summary)
    if interrupted:
        stderr_console.print("[yellow]interrupted: the files hold the part that ran[/yellow]")
        raise typer.Exit(130)

