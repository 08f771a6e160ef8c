"""Pieces shared by the command-line modules: console, common options, progress bar.

Sub-command modules (``cli_robot``, ``cli_serve``, ...) import from here, never from
:mod:`pneumaquad.cli.main`, which registers them; so any of them can be imported first.
"""

import functools
import inspect
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from pneumaquad.cli import COMMAND_STARTED
from pneumaquad.io.run_folder import RunFolderWriter
from pneumaquad.io.stage_clock import StageClock
from pneumaquad.params import ParameterError, Problem, parse_quantity
from pneumaquad.params.fields import Bounds

__all__ = [
    "MAX_CONTROL_STEPS",
    "MAX_SIMULATED_TIME",
    "MAX_WALL_TIME",
    "SIMULATED_DURATION",
    "WALL_DURATION",
    "AllowRemoteOption",
    "OutputOption",
    "ParamsOption",
    "ProfileOption",
    "SetOption",
    "check_bind",
    "check_step_count",
    "command_clock",
    "command_group",
    "console",
    "exit_if_interrupted",
    "finish_run",
    "option_range",
    "progress_bar",
    "quantity",
    "refuse_occupied_output",
    "report_command_time",
    "simulated_duration",
    "stderr_console",
]

#: Longest simulated time of one run [s] (one hour).
MAX_SIMULATED_TIME = 3600.0
#: Longest wall-clock time a server or the console may be told to run [s] (one day).
MAX_WALL_TIME = 86400.0
#: Most control steps of one run (memory for the recording stays below a few GB).
MAX_CONTROL_STEPS = 10_000_000
#: Range of a simulated duration option: (0, 3600 s].
SIMULATED_DURATION = Bounds(0.0, MAX_SIMULATED_TIME, "s")
#: Range of a wall-clock duration option: (0, 86400 s].
WALL_DURATION = Bounds(0.0, MAX_WALL_TIME, "s")

def command_group(**options: Any) -> typer.Typer:
    """A command group (``typer.Typer``) of the pneumaquad command line: help texts are
    plain text, so that bracketed units (``[s]``, ``[m/s]``) show as written instead of
    being read as Rich markup."""
    return typer.Typer(rich_markup_mode=None, **options)


#: Help placeholders of option values by parameter name (else by default or type).
NAME_PLACEHOLDERS = {
    "params": "SET", "overrides": "KEY=VALUE", "output": "PATH", "mapping": "FILE",
    "measured": "FILE", "host": "ADDRESS",
}
#: Help placeholders of option values by the value's Python type.
TYPE_PLACEHOLDERS = {"str": "TEXT", "float": "NUMBER", "int": "INTEGER", "Path": "PATH"}


def name_placeholders(command: Any) -> Any:
    """Give every option of ``command`` and its sub-commands a placeholder that says what
    to type (``SET``, ``KEY=VALUE``, ``QUANTITY`` for a value with a unit, ``NUMBER``,
    ``PATH``) where it has none, in place of the Python type typer shows (``<str>``,
    ``<list[str]>``); arguments show their name in capitals and no type. ``command`` is
    the command typer builds (``typer.main.get_command``); returns it."""
    from typer.core import TyperArgument, TyperOption

    commands = [command]
    while commands:
        current = commands.pop()
        commands.extend(getattr(current, "commands", {}).values())
        for parameter in current.params:
            if isinstance(parameter, TyperArgument) and parameter.metavar is None:
                # the argument's name in capitals, and no Python type beside it: its help
                # says what it takes
                parameter.metavar = (parameter.name or "").upper()
                parameter.display_type_rich = _no_type
            if isinstance(parameter, TyperOption) and not parameter.is_flag and (
                    parameter.metavar is None):
                value_type = parameter.bare_type().removeprefix("list[").removesuffix("]")
                parameter.metavar = (NAME_PLACEHOLDERS.get(parameter.name or "")
                                     or _quantity_placeholder(parameter.default)
                                     or TYPE_PLACEHOLDERS.get(value_type))
    return command


def _no_type(ctx: Any) -> None:
    """An argument's help row without the Python type typer adds (``<str>``)."""
    del ctx


def _quantity_placeholder(default: Any) -> str | None:
    """QUANTITY for an option whose default is a number with a unit (``"5 s"``)."""
    import re

    if isinstance(default, str) and re.fullmatch(r"-?[\d.]+(e-?\d+)? \S+", default):
        return "QUANTITY"
    return None


#: Results (figures, summaries, where files were written): standard output, so that
#: ``> file`` keeps them.
console = Console()
#: Progress, warnings and errors: standard error.
stderr_console = Console(stderr=True)

ParamsOption = Annotated[
    str, typer.Option("--params", "-p", help="Shipped set name or path to a TOML file.")
]
SetOption = Annotated[
    list[str] | None,
    typer.Option("--set", "-s", help="Override a value: section.key=value (TOML value)."),
]
OutputOption = Annotated[
    Path | None, typer.Option("--output", "-o", help="Run folder (default runs/<kind>-<time>).")
]

AllowRemoteOption = Annotated[
    bool, typer.Option("--allow-remote", help="Allow binding an address other than "
                       "loopback (there is no authentication: anyone who reaches it controls "
                       "the simulation).")
]


def check_bind(host: str, allow_remote: bool, option: str, warn: bool = True) -> None:
    """Refuse a non-loopback bind address without ``--allow-remote``; with it, print a
    warning naming the address (unless ``warn`` is False: the caller warns once bound).
    Loopback: ``localhost`` and the 127.0.0.0/8 and ::1 addresses."""
    import ipaddress

    try:
        loopback = host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:  # a host name other than localhost
        loopback = False
    if loopback:
        return
    if not allow_remote:
        raise typer.BadParameter(
            f"{host!r} is not a loopback address: the service has no authentication, so "
            "anyone who reaches it controls the simulation; pass --allow-remote to bind it "
            "anyway (or use 127.0.0.1 behind an authenticating proxy)", param_hint=option)
    if warn:
        stderr_console.print(f"[yellow]warning: listening on {host}, reachable from the network, "
                             "without authentication[/yellow]", highlight=False)


OverwriteOption = Annotated[
    bool, typer.Option("--overwrite", help="Write into an --output folder that already has "
                       "files (they are replaced where the run writes the same names).")
]


def refuse_occupied_output(command: Callable[..., Any]) -> Callable[..., Any]:
    """Give a run command (one with an ``output`` parameter) an ``--overwrite`` option and
    refuse, before anything runs, an ``--output`` folder that exists and is not empty
    without it: a run written into another run's folder would leave the old files (a
    video, a model) beside the new ones."""
    signature = inspect.signature(command, eval_str=True)
    overwrite = inspect.Parameter("overwrite", inspect.Parameter.KEYWORD_ONLY, default=False,
                                  annotation=OverwriteOption)

    @functools.wraps(command)
    def wrapper(*args: Any, overwrite: bool = False, **values: Any) -> Any:
        output = values.get("output")
        if output is not None and not overwrite and Path(output).is_dir() and any(
                Path(output).iterdir()):
            raise typer.BadParameter(
                f"{output} already has files; pass --overwrite to write into it anyway, or "
                "choose another folder (or none: runs/<kind>-<time>)", param_hint="--output")
        return command(*args, **values)

    parameters = [*signature.parameters.values(), overwrite]
    wrapper.__signature__ = signature.replace(parameters=parameters)  # type: ignore[attr-defined]
    return wrapper


ProfileOption = Annotated[
    bool,
    typer.Option("--profile", help="Write profile.json to the run folder and print where the "
                 "wall time went, stage by stage."),
]


def command_clock() -> StageClock:
    """A stage clock that starts when the command line started loading, with the time
    until now counted as ``"start-up"`` (imports, argument parsing)."""
    clock = StageClock(started=COMMAND_STARTED)
    clock.add("start-up", clock.elapsed())
    return clock


@contextmanager
def progress_bar(label: str) -> Iterator:
    """A rich progress bar; yields a callback (done, total)."""
    columns = (
        TextColumn(label),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=stderr_console, transient=True) as progress:
        task = progress.add_task(label, total=None)

        def update(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield update


def quantity(text: str, kind: str, option: str, bounds: Bounds | None = None) -> float:
    """Parse a command-line quantity such as "0.4 in" to SI.

    Parameters
    ----------
    text : str
        The option's text, a number with a unit.
    kind : str
        Kind of quantity (``"time"``, ``"length"``, ...; see ``pneumaquad.params.units``).
    option : str
        Option name for the message (``"--duration"``).
    bounds : Bounds, optional
        Range the SI value must lie in (it is always finite).

    Returns
    -------
    float
        The SI value.

    Raises
    ------
    ParameterError
        Naming the option, the text and what was expected.
    """
    value = parse_quantity(text, kind, option)
    if bounds is not None and not bounds.contains(value):
        raise ParameterError([Problem(option, text, f"should be {bounds.expectation}")])
    return value


def simulated_duration(text: str, option: str, control_step: float) -> float:
    """A simulated duration option [s]: in (0, 3600 s] and at most 10 million control steps.

    Raises
    ------
    ParameterError
        Naming the option, the text and the allowed range.
    """
    value = quantity(text, "time", option, SIMULATED_DURATION)
    check_step_count(value, control_step, option, text)
    return value


def check_step_count(duration: float, control_step: float, option: str, shown: str) -> None:
    """Refuse a simulated ``duration`` [s] of more than :data:`MAX_CONTROL_STEPS` steps."""
    steps = duration / control_step
    if steps > MAX_CONTROL_STEPS:
        raise ParameterError([Problem(
            option, shown, f"needs {steps:.3g} control steps of {control_step:g} s; expected "
            f"at most {MAX_CONTROL_STEPS:,} steps (a shorter run or a longer "
            "simulation.control_step)")])


def option_range(bounds: Bounds) -> Callable[[float | int | None], float | int | None]:
    """Typer callback for a plain-number option: finite and within ``bounds``.

    The usage error names the option, the value and the range, e.g. ``Invalid value for
    '--hold': inf should be at least 0 s and at most 3600 s``; it ends with exit status 2
    before the command runs.
    """

    def check(value: float | int | None) -> float | int | None:
        if value is not None and not bounds.contains(float(value)):
            raise typer.BadParameter(f"{value:g} should be {bounds.expectation}")
        return value

    return check


def number_in(unit: str) -> Callable[[Any], float]:
    """Typer ``parser`` of a number option whose unit is ``unit`` (``"m"``, ``"deg/s"``):
    a bare number is in ``unit`` already, a quantity with another unit of the same kind
    (``"20 cm"``, ``"0.5 rad"``) is converted to it. A text that is neither is a usage
    error naming the value and the unit expected (exit status 2)."""

    def parse(text: Any) -> float:
        if isinstance(text, (int, float)):
            return float(text)
        try:
            return float(text)
        except ValueError:
            pass
        from pneumaquad.params.units import ureg

        try:
            return float(ureg.Quantity(text).to(unit).magnitude)
        except Exception:
            raise typer.BadParameter(
                f"{text!r}: expected a number in {unit} or a quantity such as "
                f"\"1 {unit}\"") from None

    parse.__name__ = f"number in {unit}"
    return parse


def finish_run(folder: Path, summary: dict, clock: StageClock | None = None,
               profile: bool = False) -> None:
    """Print where a run went and end with 130 if it was interrupted.

    With the command's ``clock`` the real-time factor of the whole command (from its
    start, plots included) is printed after the run's own; with ``profile`` the clock's
    stages are written to ``profile.json`` in ``folder`` and printed.
    """
    console.print(f"run folder: [bold]{folder}[/bold]")
    shown = (
        "simulated time [s]",
        "wall time [s]",
        "real-time factor",
        "rmse [m]",
        "motion onset delay [s]",
        "stiction peak force [N]",
        "air consumed [NL]",
    )
    for key in shown:
        if key in summary:
            console.print(f"  {key}: {summary[key]:.6g}", markup=False, highlight=False)
    if clock is not None:
        report_command_time(folder, summary, clock, profile)
    exit_if_interrupted(summary)


def exit_if_interrupted(summary: dict) -> None:
    """End with 130 and a yellow line if the run was interrupted (Ctrl-C)."""
    if summary.get("interrupted"):
        stderr_console.print("[yellow]interrupted: the recording holds the part that ran[/yellow]")
        raise typer.Exit(130)


def report_command_time(folder: Path, summary: dict, clock: StageClock,
                        profile: bool = False) -> None:
    """Print the command's real-time factor (from its start: start-up, run, plots); with
    ``profile`` write ``profile.json`` to ``folder`` and print its stages."""
    simulated = summary.get("simulated time [s]")
    report = clock.report(simulated)
    if simulated is not None:
        console.print(f"  command real-time factor (start-up, run, plots): "
                      f"{report['real-time factor']:.3g} ({report['total [s]']:.3g} s)",
                      markup=False, highlight=False)
    if profile:
        _print_profile(folder, report)


def _print_profile(folder: Path, report: dict) -> None:
    """Write the clock's report to ``profile.json`` and print it as a table."""
    path = RunFolderWriter(folder).write_profile(report)
    console.print(f"profile: [bold]{path}[/bold]")
    for name, entry in report["stages"].items():
        console.print(f"  {name:<42} {entry['seconds']:9.4f} s {100 * entry['share']:5.1f} %"
                      f" ({entry['calls']} calls)", markup=False, highlight=False)
    console.print(f"  {'untimed':<42} {report['untimed [s]']:9.4f} s", markup=False,
                  highlight=False)
