"""Command-line interface: ``pneumaquad``.

A thin layer over the library. Values given on the command line carry units
(``--amplitude "0.4 in"``); bad values and bad parameter files end with a one-paragraph
message naming the key, the value and what was expected, and exit status 2.
"""

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from pneumaquad.cli.common import (
    MAX_SIMULATED_TIME,
    OutputOption,
    ParamsOption,
    ProfileOption,
    SetOption,
    check_step_count,
    command_clock,
    command_group,
    console,
    finish_run,
    name_placeholders,
    option_range,
    progress_bar,
    quantity,
    refuse_occupied_output,
    simulated_duration,
    stderr_console,
)
from pneumaquad.io.run_folder import create_run_folder
from pneumaquad.params import (
    ParameterError,
    list_parameter_sets,
    load_rig,
    resolved_parameters_toml,
)
from pneumaquad.params.fields import Bounds
from pneumaquad.params.loader import load_parameter_set
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig import signals
from pneumaquad.rig.signals import RecordedReferenceError
from pneumaquad.robot.errors import SimulationDivergedError


def user_errors() -> tuple[type[Exception], ...]:
    """The errors that are the user's input (a message and exit status 2, no traceback);
    imported when one is raised, so that ``--help`` loads none of the simulators."""
    from pneumaquad.rig.recording import RigDivergedError
    from pneumaquad.rig.reference import ReferenceSolverError
    from pneumaquad.robot.video import VideoError

    return (ParameterError, RecordedReferenceError, ReferenceSolverError, RigDivergedError,
            VideoError, SimulationDivergedError)

app = command_group(
    help="pneumaquad: simulator for pneumatically actuated legged robots.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
params_app = command_group(help="List, show and check parameter sets.", no_args_is_help=True)
rig_app = command_group(
    help="Single-DoF test rig (thesis ch. 4): one cylinder moving a load.", no_args_is_help=True
)
app.add_typer(params_app, name="params")
app.add_typer(rig_app, name="rig")


def _print_version(asked: bool) -> None:
    """``--version``: the installed version (pyproject.toml's), then exit."""
    if asked:
        from pneumaquad import __version__

        typer.echo(f"pneumaquad {__version__}")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[bool, typer.Option(
        "--version", help="Print the version and exit.", is_eager=True,
        callback=_print_version)] = False,
) -> None:
    """pneumaquad: simulator for pneumatically actuated legged robots."""


@params_app.command("list")
def params_list() -> None:
    """List the shipped parameter sets."""
    table = Table("name", "description")
    for name, description in list_parameter_sets().items():
        table.add_row(name, description)
    Console().print(table)


@params_app.command("show")
def params_show(
    name: Annotated[str, typer.Argument(help="Set name or TOML path.")], overrides: SetOption = None
) -> None:
    """Print a parameter set resolved to SI (loadable again with --params), numbers to 12
    significant digits (a run folder's parameters.toml keeps them exact)."""
    sys.stdout.write(resolved_parameters_toml(load_parameter_set(name, overrides or []),
                                              digits=PARAMETER_DIGITS))


#: Significant digits of the numbers ``params show`` prints.
PARAMETER_DIGITS = 12


@params_app.command("check")
def params_check(
    name: Annotated[str, typer.Argument(help="Set name or TOML path.")], overrides: SetOption = None
) -> None:
    """Validate a parameter file (rig, actuator or robot); exit 2 with the problems if it is
    not valid."""
    load_parameter_set(name, overrides or [])
    console.print(f"{name}: valid")


@rig_app.command("step")
@refuse_occupied_output
def rig_step(
    voltage: Annotated[str, typer.Argument(help='Step command, e.g. "6.0 V".')],
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    output: OutputOption = None,
    step_time: Annotated[str, typer.Option(help="Time of the step.")] = "5 s",
    duration: Annotated[str, typer.Option(help="Total duration.")] = "10 s",
    profile: ProfileOption = False,
) -> None:
    """Open-loop voltage step with the thesis protocol (opposite saturation, then the step)."""
    clock = command_clock()
    setup = load_rig(params, overrides or [])
    command = valve_voltage(voltage, setup)
    valve = setup.actuator.valve
    total = simulated_duration(duration, "--duration", setup.simulation.control_step)
    at = quantity(
        step_time,
        "time",
        "--step-time",
        Bounds(0.0, total, "s", lower_inclusive=True, upper_text=f"--duration ({total:g} s)"),
    )
    signal = signals.thesis_step_command(
        command,
        valve.offset_voltage,
        valve.min_voltage,
        valve.max_voltage,
        setup.simulation.control_step,
        at,
        total,
    )
    folder = create_run_folder(output, "rig-step")
    from pneumaquad.reporting.rig_experiment import run_rig_experiment

    with progress_bar("rig step") as update:
        _, summary = run_rig_experiment(
            setup, folder, signal, False, f"open-loop step to {command:g} V", at, update,
            clock=clock,
        )
    finish_run(folder, summary, clock, profile)


#: Longest spacer sweep, all held voltages together [s] (one hour).
MAX_SPACER_TIME = 3600.0


def held_voltages(text: str, valve_range: tuple[float, float]) -> list[float]:
    """Comma-separated held commands ("4 V,4.5 V,5.5 V") [V], each within the valve range.

    Raises
    ------
    ParameterError
        Naming ``VOLTAGES``, the item and the expected range.
    """
    low, high = valve_range
    items = [item.strip() for item in text.split(",")]
    if not all(items):
        raise ParameterError.single(
            "VOLTAGES", text, 'one voltage or several separated by commas, e.g. "4 V,5.5 V"'
        )
    values = [quantity(item, "voltage", "VOLTAGES") for item in items]
    for item, value in zip(items, values, strict=True):
        if not low <= value <= high:
            raise ParameterError.single("VOLTAGES", item, f"a voltage within [{low:g}, {high:g}] V")
    return values


@rig_app.command("spacer")
@refuse_occupied_output
def rig_spacer(
    voltages: Annotated[
        str,
        typer.Argument(
            help='Held command, e.g. "5.5 V", or a sweep of several held one after the other, '
            'e.g. "4 V,4.5 V,4.85 V,5.25 V,5.55 V,6 V" (input for fit valve --spacer).'
        ),
    ],
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    output: OutputOption = None,
    duration: Annotated[str, typer.Option(help="Time at each held voltage.")] = "5 s",
    profile: ProfileOption = False,
) -> None:
    """Fixed piston (spacer, thesis 4.2.1) at held voltages: pressures settle on Fig. 23.

    One recording holds every voltage in turn for --duration each; `pneumaquad fit valve
    --spacer RUN_FOLDER` fits the input-pressure curves from it (three voltages at least,
    two of them in each port's transition).
    """
    clock = command_clock()
    setup = load_rig(params, [*(overrides or []), "rig.spacer=true"])
    valve = setup.actuator.valve
    levels = held_voltages(voltages, (valve.min_voltage, valve.max_voltage))
    hold = quantity(duration, "time", "--duration")
    control_step = setup.simulation.control_step
    if not control_step <= hold <= MAX_SPACER_TIME / len(levels):
        raise ParameterError.single(
            "--duration",
            duration,
            f"a time per voltage from one control step ({control_step:g} s) to "
            f"{MAX_SPACER_TIME / len(levels):g} s ({MAX_SPACER_TIME:g} s for the "
            f"{len(levels)} voltages together)",
        )
    signal = signals.step_train(levels, hold, control_step)
    shown = ", ".join(f"{value:g} V" for value in levels)
    folder = create_run_folder(output, "rig-spacer")
    from pneumaquad.reporting.rig_experiment import run_rig_experiment

    with progress_bar("rig spacer") as update:
        _, summary = run_rig_experiment(
            setup,
            folder,
            signal,
            False,
            f"fixed piston at {shown}",
            None,
            update,
            extra={"held voltages [V]": levels, "time per voltage [s]": hold},
            clock=clock,
        )
    finish_run(folder, summary, clock, profile)


@rig_app.command("track")
@refuse_occupied_output
def rig_track(
    reference: Annotated[
        str, typer.Argument(help="Reference shape: sine, step, trapezoid, chirp or file.")
    ],
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    output: OutputOption = None,
    mean: Annotated[str, typer.Option(help="Mean position (sine, chirp).")] = "0.875 in",
    amplitude: Annotated[str, typer.Option(help="Amplitude (sine, chirp).")] = "0.4 in",
    frequency: Annotated[str, typer.Option(help="Frequency (sine; chirp start).")] = "0.5 Hz",
    end_frequency: Annotated[str, typer.Option(help="Chirp end frequency.")] = "3 Hz",
    duration: Annotated[str, typer.Option(help="Duration (sine, chirp).")] = "10 s",
    levels: Annotated[
        str, typer.Option(help="Step levels, comma separated (step); low,high (trapezoid).")
    ] = "0.4 in,1.4 in,0.6 in,1.2 in,0.875 in",
    dwell: Annotated[str, typer.Option(help="Time per level (step); hold (trapezoid).")] = "2 s",
    ramp: Annotated[str, typer.Option(help="Ramp time (trapezoid).")] = "1 s",
    cycles: Annotated[
        int,
        typer.Option(
            help="Cycles (trapezoid), 1 to 10000.",
            callback=option_range(Bounds(1, 10000, lower_inclusive=True)),
        ),
    ] = 2,
    file: Annotated[Path | None, typer.Option(help="CSV or .mat reference (file).")] = None,
    time_column: Annotated[str, typer.Option(help="Time column in --file.")] = "time",
    time_unit: Annotated[str, typer.Option(help="Unit of the time column (s, ms...).")] = "s",
    position_column: Annotated[str, typer.Option(help="Position column in --file.")] = "position",
    position_unit: Annotated[str, typer.Option(help="Unit of the position column.")] = "m",
    profile: ProfileOption = False,
) -> None:
    """Closed-loop position tracking with the PID of the parameter file."""
    clock = command_clock()
    setup = load_rig(params, overrides or [])
    signal = build_reference(
        reference,
        setup,
        mean,
        amplitude,
        frequency,
        end_frequency,
        duration,
        levels,
        dwell,
        ramp,
        cycles,
        file,
        time_column,
        position_column,
        position_unit,
        time_unit,
    )
    folder = create_run_folder(output, f"rig-track-{reference}")
    from pneumaquad.reporting.rig_experiment import run_rig_experiment

    with progress_bar(f"rig track {reference}") as update:
        _, summary = run_rig_experiment(
            setup, folder, signal, True, f"closed-loop {reference} tracking", None, update,
            clock=clock,
        )
    finish_run(folder, summary, clock, profile)


def valve_voltage(text: str, setup: RigSetup) -> float:
    """The VOLTAGE argument [V]: a voltage within the valve's [min_voltage, max_voltage]."""
    valve = setup.actuator.valve
    return quantity(
        text,
        "voltage",
        "VOLTAGE",
        Bounds(valve.min_voltage, valve.max_voltage, "V", lower_inclusive=True),
    )


def build_reference(
    reference: str,
    setup: RigSetup,
    mean: str,
    amplitude: str,
    frequency: str,
    end_frequency: str,
    duration: str,
    levels: str,
    dwell: str,
    ramp: str,
    cycles: int,
    file: Path | None,
    time_column: str,
    position_column: str,
    position_unit: str,
    time_unit: str = "s",
) -> np.ndarray:
    """Position reference [m] per control step for ``rig track``.

    Every option is checked before anything is built: positions within [0, stroke],
    frequencies in (0, the Nyquist frequency of the control step], times positive and at
    most an hour, and the whole reference at most an hour of simulated time.

    Raises
    ------
    ParameterError
        Naming the option, its text and what was expected.
    """
    dt = setup.simulation.control_step
    stroke = setup.actuator.cylinder.stroke
    position = Bounds(0.0, stroke, "m", lower_inclusive=True,
                      upper_text=f"cylinder.stroke ({stroke:g} m)")
    nyquist = 0.5 / dt
    rate = Bounds(0.0, nyquist, "Hz", upper_text=f"{nyquist:g} Hz (half the control rate)")
    span = Bounds(0.0, MAX_SIMULATED_TIME, "s")
    ramp_span = Bounds(0.0, MAX_SIMULATED_TIME, "s", lower_inclusive=True)

    def length(text: str, option: str) -> float:
        return quantity(text, "length", option, position)

    def level_list(count: int | None = None) -> list[float]:
        return [length(level, "--levels") for level in levels.split(",")[:count]]

    def total_time(seconds: float, option: str, shown: str) -> None:
        if seconds > MAX_SIMULATED_TIME:
            raise ParameterError.single(
                option, shown, f"a reference of at most {MAX_SIMULATED_TIME:g} s in all "
                f"(this one lasts {seconds:.4g} s)")
        check_step_count(seconds, dt, option, shown)

    def sine() -> np.ndarray:
        middle, swing = length(mean, "--mean"), length(amplitude, "--amplitude")
        start = quantity(frequency, "frequency", "--frequency", rate)
        seconds = simulated_duration(duration, "--duration", dt)
        return signals.sine(middle, swing, start, seconds, dt)

    def chirp() -> np.ndarray:
        middle, swing = length(mean, "--mean"), length(amplitude, "--amplitude")
        start = quantity(frequency, "frequency", "--frequency", rate)
        end = quantity(end_frequency, "frequency", "--end-frequency", rate)
        seconds = simulated_duration(duration, "--duration", dt)
        return signals.chirp(middle, swing, start, end, seconds, dt)

    def step() -> np.ndarray:
        values = level_list()
        hold = quantity(dwell, "time", "--dwell", span)
        total_time(hold * len(values), "--dwell", dwell)
        return signals.step_train(values, hold, dt)

    def trapezoid() -> np.ndarray:
        low, high = level_list(2)
        ramp_time = quantity(ramp, "time", "--ramp", ramp_span)
        hold = quantity(dwell, "time", "--dwell", span)
        total_time(2.0 * (ramp_time + hold) * cycles, "--cycles", str(cycles))
        return signals.trapezoid(low, high, ramp_time, hold, cycles, dt)

    def recorded() -> np.ndarray:
        return signals.recorded_reference(
            file if file is not None else Path(""),
            time_column,
            position_column,
            quantity(f"1 {position_unit}", "length", "--position-unit"),
            dt,
            quantity(f"1 {time_unit}", "time", "--time-unit"),
        )

    builders: dict[str, Callable[[], np.ndarray]] = {
        "sine": sine,
        "chirp": chirp,
        "step": step,
        "trapezoid": trapezoid,
        "file": recorded,
    }
    if reference not in builders:
        raise ParameterError.single(
            "REFERENCE", reference, "one of sine, step, trapezoid, chirp, file"
        )
    if reference == "trapezoid" and len(levels.split(",")) < 2:
        raise ParameterError.single("--levels", levels, "two lengths: low,high")
    return builders[reference]()


@app.command("valve-fit")
def valve_fit() -> None:
    """Run the thesis's App. B.2 equivalent-area fit and print both ports' polynomials."""
    from pneumaquad.core.valve_fit import thesis_port_polynomials

    table = Table("port", "side", "coefficients (m^2/V^n), highest power first")
    for port in (1, 2):
        negative, positive = thesis_port_polynomials(port)
        table.add_row(str(port), "u_c <= 0", ", ".join(f"{c:.4g}" for c in negative))
        table.add_row(str(port), "u_c > 0", ", ".join(f"{c:.4g}" for c in positive))
    Console().print(table)


@app.command("demo")
def demo(
    output: Annotated[Path, typer.Option("--output", "-o", help="Report folder.")] = Path(
        "runs/demo"
    ),
) -> None:
    """Representative rig runs and a report folder (report.md, report.html, PNGs, JSON)."""
    from pneumaquad.demo.run import run_demo

    with progress_bar("demo") as update:
        report = run_demo(output, update)
    console.print(f"report: [bold]{report}[/bold]")


def _register_robot_commands() -> None:
    from pneumaquad.cli.console import console_command
    from pneumaquad.cli.export import export_app
    from pneumaquad.cli.fit import fit_app
    from pneumaquad.cli.report import report_command
    from pneumaquad.cli.robot import leg_app, robot_app, video_command
    from pneumaquad.cli.serve import serve_app
    from pneumaquad.cli.study import study_app

    app.add_typer(fit_app, name="fit")
    app.command("console")(console_command)
    app.add_typer(export_app, name="export")
    app.command("report")(report_command)
    app.add_typer(leg_app, name="leg")
    app.add_typer(robot_app, name="robot")
    app.add_typer(serve_app, name="serve")
    app.add_typer(study_app, name="study")
    app.command("video")(video_command)


_register_robot_commands()


def main() -> None:
    """Entry point: run the app; user errors print a message and exit with status 2."""
    try:
        name_placeholders(typer.main.get_command(app))()
    except Exception as error:
        if not isinstance(error, user_errors()):
            raise
        stderr_console.print("error:", style="bold red", end=" ")
        stderr_console.print(str(error), highlight=False, markup=False, soft_wrap=True)
        sys.exit(2)
