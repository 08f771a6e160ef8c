"""Command line for parameter identification: ``pneumaquad fit friction|valve``.

A thin layer over `pneumaquad.identification`. Inputs are rig run folders (or their
``recording.parquet``/``recording.csv``) or measured CSV/MAT files with a column mapping
(`pneumaquad.measured`); the output is a parameter file that ``--params`` accepts.
User errors (bad files, mappings, parameters, unusable data) end with a message and exit
status 2, without a traceback.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn
from rich.table import Table

from pneumaquad.analysis import find_steps
from pneumaquad.cli_common import ParamsOption, SetOption, console
from pneumaquad.identification.friction import (
    FrictionPoints,
    fit_coulomb_viscous,
    kinetic_friction_points,
    stiction_from_step,
    summarize_stiction,
)
from pneumaquad.identification.preprocess import IdentificationError
from pneumaquad.identification.report import (
    FitResult,
    format_r_squared,
    updates_from_fit,
    write_parameter_file,
)
from pneumaquad.identification.valve import (
    area_polynomial_updates,
    areas_table,
    equivalent_area_for_step,
    fit_area_polynomials,
    input_pressure_curves,
)
from pneumaquad.measured import ColumnMapping, MeasuredDataError, load_mapping, read_measured
from pneumaquad.params import ParameterError, load_rig, parse_quantity
from pneumaquad.params.schema import RigSetup
from pneumaquad.recording import read_recording

__all__ = ["fit_app"]

USER_ERRORS = (ParameterError, MeasuredDataError, IdentificationError, OSError)
#: Smallest command jump taken as a step [V].
COMMAND_THRESHOLD = 0.05

fit_app = typer.Typer(
    help="Identify friction and valve parameters from recordings (thesis 4.2.2-4.2.3).",
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
        console.print("error:", style="bold red", end=" ")
        console.print(str(error), highlight=False, markup=False, soft_wrap=True)
        raise typer.Exit(2) from None


@contextmanager
def progress_bar(label: str, total: int) -> Iterator[Any]:
    """A transient rich progress bar on stderr; yields a function advancing it by one."""
    columns = (TextColumn(label), BarColumn(), MofNCompleteColumn())
    with Progress(*columns, console=console, transient=True) as progress:
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


def read_inputs(paths: list[Path], mapping_path: Path | None) -> list[dict[str, np.ndarray]]:
    """Read every input (see `read_input`)."""
    mapping = load_mapping(mapping_path) if mapping_path is not None else None
    return [read_input(Path(path), mapping) for path in paths]


def show_fit(fit: FitResult) -> None:
    """Print a fit's parameters, standard errors and statistics as a table."""
    table = Table("parameter", "value", "std. error", title=fit.name)
    for key, value, error in fit.rows():
        table.add_row(key, f"{value:.6g}", f"{error:.2g}")
    console.print(table)
    console.print(
        f"  n = {fit.n_points}, R^2 = {format_r_squared(fit.r_squared)}, "
        f"residual RMS = {fit.residual_rms:.4g} {fit.residual_unit}",
        highlight=False,
    )


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
        stiction = summarize_stiction(estimates)
        sliding = fit_coulomb_viscous(points.velocity, points.friction)
        for fit in (stiction, sliding):
            show_fit(fit)
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


@fit_app.command("valve")
def fit_valve(
    output: OutputOption,
    spacer: Annotated[
        list[Path] | None,
        typer.Option(help="Fixed-piston recording at held commands (repeat the option)."),
    ] = None,
    steps: Annotated[
        list[Path] | None,
        typer.Option(help="Open-loop step recording for equivalent areas (repeatable)."),
    ] = None,
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    mapping: MappingOption = None,
    mode: Annotated[
        str, typer.Option(help="Area unknowns: per_port, or scale (one factor on both).")
    ] = "per_port",
    duration: Annotated[str, typer.Option(help="Fitted time after each step.")] = "0.6 s",
) -> None:
    """Input-pressure cutoffs from spacer tests, equivalent areas and polynomials from steps."""
    with user_errors():
        if not spacer and not steps:
            raise IdentificationError("give --spacer and/or --steps recordings")
        setup: RigSetup = load_rig(params, overrides or [])
        segment = _quantity(duration, "time", "--duration")
        fits: list[FitResult] = []
        updates: dict[str, Any] = {}
        if spacer:
            curves = input_pressure_curves(read_inputs(spacer, mapping), setup)
            for port, fit in curves.fits.items():
                show_fit(fit)
                fits.append(fit)
                updates.update(updates_from_fit(fit, f"valve.port{port}"))
            setup = load_rig(params, [*(overrides or []), *_cutoff_overrides(curves.fits)])
        if steps:
            data = read_inputs(steps, mapping)
            jobs = [(recording, time) for recording in data for time in step_times(recording)]
            area_fits = []
            with progress_bar("equivalent areas", len(jobs)) as advance:
                for recording, time in jobs:
                    area_fits.append(
                        equivalent_area_for_step(
                            setup, recording, step_time=time, duration=segment, mode=mode
                        )
                    )
                    advance()
            table = Table("centered voltage [V]", "port 1 area [m^2]", "port 2 area [m^2]")
            for item in area_fits:
                table.add_row(
                    f"{item.centered_voltage:+.3f}", f"{item.areas[1]:.4g}", f"{item.areas[2]:.4g}"
                )
            console.print(table)
            fits.extend(item.fit for item in area_fits)
            voltages, areas = areas_table(area_fits)
            try:
                polynomials = fit_area_polynomials(voltages, areas)
            except IdentificationError as error:
                console.print(f"area polynomials not updated: {error}", highlight=False)
            else:
                updates.update(area_polynomial_updates(polynomials))
        if not updates:
            raise IdentificationError("nothing was fitted; no parameter file written")
        written = write_parameter_file(
            params, updates, output, fits=fits, overrides=overrides or []
        )
    console.print(f"parameters: [bold]{written}[/bold]")
