"""Command line for parameter identification: ``pneumaquad fit friction|valve|controller``.

A thin layer over `pneumaquad.identification`. Inputs are rig run folders (or their
``recording.parquet``/``recording.csv``) or measured CSV/MAT files with a column mapping
(`pneumaquad.io.measured`); the output is a parameter file that ``--params`` accepts.
User errors (bad files, mappings, parameters, unusable data) end with a message and exit
status 2, without a traceback. A fit that ran but whose own checks say it failed (a
parameter the data do not determine, large residuals) ends with a message naming the fit
and the parameter and exit status 1, and nothing is written unless ``--force``.
``fit controller`` is in `pneumaquad.cli.fit_controller`.
"""

from __future__ import annotations

import glob
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn
from rich.table import Table

from pneumaquad.analysis import find_steps
from pneumaquad.analysis.fits import FitResult, check_standard_errors, format_r_squared
from pneumaquad.cli.common import ParamsOption, SetOption, command_group, console, stderr_console
from pneumaquad.identification.equivalent_area import AREA_MODES, START_TEMPERATURE_SOURCES
from pneumaquad.identification.friction import (
    FrictionPoints,
    fit_coulomb_viscous,
    kinetic_friction_points,
    stiction_from_step,
    summarize_stiction,
)
from pneumaquad.identification.preprocess import IdentificationError
from pneumaquad.identification.report import updates_from_fit, write_parameter_file
from pneumaquad.identification.valve import (
    area_polynomial_updates,
    areas_table,
    equivalent_area_for_step,
    fit_area_polynomials,
    input_pressure_curves,
)
from pneumaquad.io.measured import ColumnMapping, MeasuredDataError, load_mapping, read_measured
from pneumaquad.io.run_folder import read_recording
from pneumaquad.params import ParameterError, load_rig, parse_quantity
from pneumaquad.params.schema import RigSetup

__all__ = ["fit_app"]

USER_ERRORS = (ParameterError, MeasuredDataError, IdentificationError, OSError)
#: Smallest command jump taken as a step [V].
COMMAND_THRESHOLD = 0.05
#: Exit status of a fit that ran but failed its own checks (nothing written).
FIT_FAILED_STATUS = 1

fit_app = command_group(
    help="Identify friction and valve parameters (thesis 4.2.2-4.2.3) and the controller "
    "from recordings.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

RecordingsArgument = Annotated[
    list[Path],
    typer.Argument(help="Run folders, recording.parquet/.csv files, or measured files."),
]
OutputOption = Annotated[
    Path, typer.Option("--output", "-o", help="Parameter file (TOML) to write.")
]
ForceOption = Annotated[
    bool,
    typer.Option(
        "--force",
        help="Write the parameter file even when a fit failed its checks (they are listed "
        "in the file's header).",
    ),
]
MappingOption = Annotated[
    Path | None,
    typer.Option("--mapping", "-m", help="Column mapping TOML for measured CSV/MAT files."),
]


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn the library's user-facing errors into a message and exit status 2."""
    try:
        yield
    except USER_ERRORS as error:
        stderr_console.print("error:", style="bold red", end=" ")
        stderr_console.print(str(error), highlight=False, markup=False, soft_wrap=True)
        raise typer.Exit(2) from None


@contextmanager
def progress_bar(label: str, total: int) -> Iterator[Any]:
    """A transient rich progress bar on stderr; yields a function advancing it by one."""
    columns = (TextColumn(label), BarColumn(), MofNCompleteColumn())
    with Progress(*columns, console=stderr_console, transient=True) as progress:
        task = progress.add_task(label, total=total)
        yield lambda: progress.advance(task)


def read_input(path: Path, mapping: ColumnMapping | None) -> dict[str, np.ndarray]:
    """A recording from a run folder, a project recording file, or a mapped measured file."""
    if not path.exists():
        raise IdentificationError(f"recording {str(path)!r} does not exist")
    if mapping is not None and not path.is_dir():
        return read_measured(path, mapping)
    if path.is_dir() or path.suffix.lower() in (".parquet", ".csv"):
        try:
            return read_recording(path)
        except ValueError as error:  # unreadable numbers or an empty file
            raise IdentificationError(f"{path}: {error}") from error
    raise IdentificationError(f"{path}: a measured file needs a column mapping (--mapping)")


def expand_paths(paths: Sequence[Path], option: str) -> list[Path]:
    """Paths as given, with (quoted) glob patterns such as ``'lab/step-*.csv'`` expanded.

    Raises
    ------
    IdentificationError
        Naming ``option`` and the pattern when a pattern matches no file.
    """
    expanded: list[Path] = []
    for path in paths:
        text = str(path)
        if Path(text).exists() or not glob.has_magic(text):
            expanded.append(Path(text))
            continue
        matches = sorted(glob.glob(text))
        if not matches:
            raise IdentificationError(f"{option}: the pattern {text!r} matches no file")
        expanded.extend(Path(match) for match in matches)
    return expanded


def read_inputs(
    paths: Sequence[Path], mapping_path: Path | None, option: str = "RECORDINGS"
) -> list[dict[str, np.ndarray]]:
    """Read every input (see `read_input`); glob patterns are expanded (`expand_paths`)."""
    mapping = load_mapping(mapping_path) if mapping_path is not None else None
    return [read_input(path, mapping) for path in expand_paths(paths, option)]


def show_fit(fit: FitResult) -> None:
    """Print a fit's parameters, standard errors and statistics as a table, and its problems."""
    title = fit.name + (" [FAILED]" if fit.failed else "")
    table = Table("parameter", "value", "std. error", title=title)
    for key, value, error in fit.rows():
        table.add_row(key, f"{value:.6g}", f"{error:.2g}")
    console.print(table)
    console.print(
        f"  n = {fit.n_points}, R^2 = {format_r_squared(fit.r_squared)}, "
        f"residual RMS = {fit.residual_rms:.4g} {fit.residual_unit}",
        highlight=False,
    )
    show_problems(fit)


def show_problems(fit: FitResult) -> None:
    """Print why a fit failed its checks, one line per problem."""
    for problem in fit.problems:
        console.print("  failed:", style="bold red", end=" ")
        console.print(problem, highlight=False, markup=False, soft_wrap=True)


def refuse_failed_fits(fits: Sequence[FitResult], force: bool) -> None:
    """End with `FIT_FAILED_STATUS` if any fit failed its checks, unless ``force``."""
    failed = [fit for fit in fits if fit.failed]
    if not failed:
        return
    names = ", ".join(f"'{fit.name}'" for fit in failed)
    if force:
        console.print(
            f"warning: writing despite failed fits ({names}) because of --force; the "
            "problems are listed in the file's header",
            style="yellow",
            highlight=False,
        )
        return
    stderr_console.print("error:", style="bold red", end=" ")
    stderr_console.print(
        f"{len(failed)} fit(s) failed their checks ({names}): see the 'failed:' lines "
        "above. No parameter file written (--force writes it anyway).",
        highlight=False,
        markup=False,
        soft_wrap=True,
    )
    raise typer.Exit(FIT_FAILED_STATUS)


def step_times(recording: Mapping[str, np.ndarray]) -> list[float]:
    """Start times of the command steps of a recording [s]."""
    return [
        segment.start_time
        for segment in find_steps(
            recording["time [s]"], recording["command [V]"], COMMAND_THRESHOLD
        )
    ]


def _quantity(text: str, kind: str, option: str) -> float:
    return parse_quantity(text, kind, option)


@fit_app.command("friction")
def fit_friction(
    recordings: RecordingsArgument,
    output: OutputOption,
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    mapping: MappingOption = None,
    end_margin: Annotated[
        str, typer.Option(help="Samples this close to an end stop are left out.")
    ] = "2 mm",
    min_speed: Annotated[str, typer.Option(help="Slowest sliding sample used.")] = "0.01 m/s",
    max_acceleration: Annotated[
        str, typer.Option(help="Largest |acceleration| of a constant-velocity sample.")
    ] = "2 m/s^2",
    velocity_threshold: Annotated[
        str, typer.Option(help="Speed that counts as motion onset.")
    ] = "0.01 m/s",
    force: ForceOption = False,
) -> None:
    """Stiction from open-loop step peaks, Coulomb and viscous friction from sliding."""
    with user_errors():
        setup = load_rig(params, overrides or [])
        margin = _quantity(end_margin, "length", "--end-margin")
        slowest = _quantity(min_speed, "velocity", "--min-speed")
        largest = _quantity(max_acceleration, "acceleration", "--max-acceleration")
        threshold = _quantity(velocity_threshold, "velocity", "--velocity-threshold")
        data = read_inputs(recordings, mapping)
        steps = [(recording, time) for recording in data for time in step_times(recording)]
        if not steps:
            raise IdentificationError("the recordings hold no command step")
        estimates = []
        with progress_bar("stiction peaks", len(steps)) as advance:
            for recording, time in steps:
                try:
                    estimates.append(
                        stiction_from_step(
                            recording, setup, step_time=time, velocity_threshold=threshold
                        )
                    )
                except IdentificationError as error:
                    console.print(f"  skipped step at {time:g} s: {error}", highlight=False)
                advance()
        points = FrictionPoints.concatenate(
            kinetic_friction_points(
                recording,
                setup,
                min_speed=slowest,
                max_acceleration=largest,
                end_margin=margin,
            )
            for recording in data
        )
        clear = sum(estimate.clear_peak for estimate in estimates)
        console.print(f"stiction: {clear} of {len(steps)} steps show a clear peak", highlight=False)
        stiction = check_standard_errors(summarize_stiction(estimates))
        sliding = check_standard_errors(fit_coulomb_viscous(points.velocity, points.friction))
        for fit in (stiction, sliding):
            show_fit(fit)
        refuse_failed_fits((stiction, sliding), force)
        updates = {
            **updates_from_fit(stiction, "friction"),
            **updates_from_fit(sliding, "friction"),
        }
        written = write_parameter_file(
            params, updates, output, fits=(stiction, sliding), overrides=overrides or []
        )
    console.print(f"parameters: [bold]{written}[/bold]")


def _cutoff_overrides(fits: Mapping[int, FitResult]) -> list[str]:
    overrides = []
    for port, fit in fits.items():
        for key, value in updates_from_fit(fit, f"valve.port{port}").items():
            overrides.append(f'{key}="{value}"')
    return overrides


def start_temperature_setting(text: str) -> str | tuple[float, float]:
    """The ``--start-temperature`` option: a source name, or one or two temperatures [K].

    Raises
    ------
    ParameterError
        Naming the option and the value.
    """
    name = text.strip().lower()
    if name in START_TEMPERATURE_SOURCES:
        return name
    expected = (
        f"one of {', '.join(START_TEMPERATURE_SOURCES)}, a temperature such as \"380 K\", or "
        'cap and rod temperatures such as "380 K,200 K"'
    )
    parts = [part.strip() for part in text.split(",")]
    if len(parts) not in (1, 2) or not any(character.isdigit() for character in text):
        raise ParameterError.single("--start-temperature", text, expected)
    values = [_quantity(part, "temperature", "--start-temperature") for part in parts]
    if any(value <= 0.0 for value in values):
        raise ParameterError.single("--start-temperature", text, "temperatures above 0 K")
    return (values[0], values[-1])


@fit_app.command("valve")
def fit_valve(
    output: OutputOption,
    spacer: Annotated[
        list[Path] | None,
        typer.Option(
            help="Fixed-piston recording at one or several held commands (a spacer sweep); "
            "repeat the option or quote a glob pattern."
        ),
    ] = None,
    steps: Annotated[
        list[Path] | None,
        typer.Option(
            help="Open-loop step recording for equivalent areas (any uniform sample rate); "
            "repeat the option or quote a glob pattern."
        ),
    ] = None,
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    mapping: MappingOption = None,
    mode: Annotated[
        str, typer.Option(help="Area unknowns: per_port, or scale (one factor on both).")
    ] = "per_port",
    duration: Annotated[str, typer.Option(help="Fitted time after each step.")] = "0.6 s",
    start_temperature: Annotated[
        str,
        typer.Option(
            help="Gas temperatures at each step's start: auto (recorded temperature columns, "
            "else hold), hold (simulate the hold before the step, adiabatic model), supply, "
            'recorded, or "380 K" / "380 K,200 K" (cap, rod).'
        ),
    ] = "auto",
    force: ForceOption = False,
) -> None:
    """Input-pressure cutoffs from spacer tests, equivalent areas and polynomials from steps.

    Each fit checks itself; a failed fit (a parameter the data do not determine, large
    residuals, unsettled spacer pressures) ends with exit status 1 and no file unless
    --force.
    """
    with user_errors():
        if not spacer and not steps:
            raise IdentificationError("give --spacer and/or --steps recordings")
        setup: RigSetup = load_rig(params, overrides or [])
        segment = _quantity(duration, "time", "--duration")
        if not segment > 0.0:
            raise ParameterError.single("--duration", duration, "a positive time")
        if mode not in AREA_MODES:
            raise ParameterError.single("--mode", mode, " or ".join(AREA_MODES))
        temperature = start_temperature_setting(start_temperature)
        fits: list[FitResult] = []
        updates: dict[str, Any] = {}
        if spacer:
            curves = input_pressure_curves(read_inputs(spacer, mapping, "--spacer"), setup)
            for port, fit in curves.fits.items():
                show_fit(fit)
                fits.append(fit)
                updates.update(updates_from_fit(fit, f"valve.port{port}"))
            if any(fit.failed for fit in curves.fits.values()):
                console.print(
                    "input-pressure fit failed: the steps are fitted with the cutoffs of "
                    f"{params!r}",
                    highlight=False,
                )
            else:
                setup = load_rig(params, [*(overrides or []), *_cutoff_overrides(curves.fits)])
        if steps:
            data = read_inputs(steps, mapping, "--steps")
            jobs = [(recording, time) for recording in data for time in step_times(recording)]
            if not jobs:
                raise IdentificationError("the --steps recordings hold no command step")
            area_fits = []
            with progress_bar("equivalent areas", len(jobs)) as advance:
                for recording, time in jobs:
                    area_fits.append(
                        equivalent_area_for_step(
                            setup,
                            recording,
                            step_time=time,
                            duration=segment,
                            mode=mode,
                            start_temperature=temperature,
                        )
                    )
                    advance()
            table = Table(
                "centered voltage [V]",
                "port 1 area [m^2]",
                "port 2 area [m^2]",
                "start T cap/rod [K]",
                "check",
                title="equivalent areas per step",
            )
            for item in area_fits:
                table.add_row(
                    f"{item.centered_voltage:+.3f}",
                    f"{item.areas[1]:.4g}",
                    f"{item.areas[2]:.4g}",
                    f"{item.start_temperatures[0]:.0f}/{item.start_temperatures[1]:.0f} "
                    f"({item.temperature_source})",
                    "FAILED" if item.failed else "ok",
                )
            console.print(table)
            for item in area_fits:
                show_problems(item.fit)
            fits.extend(item.fit for item in area_fits)
            voltages, areas = areas_table(area_fits)
            try:
                polynomials = fit_area_polynomials(voltages, areas)
            except IdentificationError as error:
                console.print(f"area polynomials not updated: {error}", highlight=False)
            else:
                updates.update(area_polynomial_updates(polynomials))
        refuse_failed_fits(fits, force)
        if not updates:
            raise IdentificationError("nothing was fitted; no parameter file written")
        written = write_parameter_file(
            params, updates, output, fits=fits, overrides=overrides or []
        )
    console.print(f"parameters: [bold]{written}[/bold]")


def _register_controller_command() -> None:
    """``fit controller`` lives in its own module, which uses this one's helpers."""
    from pneumaquad.cli.fit_controller import fit_controller_command

    fit_app.command("controller")(fit_controller_command)


_register_controller_command()
