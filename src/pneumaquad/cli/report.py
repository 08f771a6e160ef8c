"""Command-line interface of the reports: ``pneumaquad report RUN [--measured DATA]`` and
``pneumaquad report --cost-table``.

A thin layer over :mod:`pneumaquad.reporting`. User errors (missing run folder, malformed
parameter or measured-data files) print one message and exit with status 2. This module
imports nothing from :mod:`pneumaquad.cli.main`, so that module can register ``report_command``
without an import cycle.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from pneumaquad.cli.common import (
    MAX_SIMULATED_TIME,
    console,
    number_in,
    option_range,
    progress_bar,
    stderr_console,
)
from pneumaquad.io.measured import MeasuredDataError
from pneumaquad.params import ParameterError
from pneumaquad.params.fields import Bounds
from pneumaquad.reporting.run_folder import ReportError

__all__ = ["REPORT_ERRORS", "report_command"]

#: Exceptions that are the user's input problems: message and exit status 2.
REPORT_ERRORS = (ReportError, ParameterError, MeasuredDataError)



def _fail(error: Exception) -> None:
    stderr_console.print("error:", style="bold red", end=" ")
    stderr_console.print(str(error), highlight=False, markup=False, soft_wrap=True)
    raise typer.Exit(2)


def _unit_system(value: str) -> str:
    """Typer callback of ``--units``: one of the report unit systems (lower case)."""
    from pneumaquad.reporting.display_units import UNIT_SYSTEMS

    if value.lower() not in UNIT_SYSTEMS:
        raise typer.BadParameter(f"{value!r}: expected one of {', '.join(UNIT_SYSTEMS)}")
    return value.lower()


def report_command(
    run: Annotated[
        Path | None, typer.Argument(help="Run folder of a rig or robot experiment.")
    ] = None,
    measured: Annotated[
        Path | None,
        typer.Option("--measured", "-m", help="Measured recording (CSV or MAT), rig runs."),
    ] = None,
    mapping: Annotated[
        Path | None,
        typer.Option("--mapping", help="TOML column mapping of the measured recording."),
    ] = None,
    time_offset: Annotated[
        float,
        typer.Option("--time-offset", help="Added to the measured time stamps [s], "
                     "-86400 to 86400.",
                     callback=option_range(Bounds(-86400.0, 86400.0, "s",
                                                  lower_inclusive=True)),
                     parser=number_in("s"), metavar="QUANTITY"),
    ] = 0.0,
    units: Annotated[
        str,
        typer.Option("--units", help="Units of every figure, table and text of a run's "
                     "report: si (m, mm, kPa, N) or us (the thesis's in, psia, psig, lbf).",
                     callback=_unit_system, metavar="si|us"),
    ] = "si",
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="Report folder (default RUN/report, or "
                     "runs/cost-table with --cost-table, runs/thesis-comparison with "
                     "--thesis-comparison)."),
    ] = None,
    cost_table: Annotated[
        bool,
        typer.Option("--cost-table", help="Instead of a run: time the rig model with "
                     "components simplified (thesis Table 3) and report that."),
    ] = False,
    thesis_comparison: Annotated[
        bool,
        typer.Option("--thesis-comparison", help="Instead of a run: measure every "
                     "closed-loop claim of thesis 4.3 and 5.5 for our tuning and the thesis "
                     "controller set, and write thesis-comparison.md (docs/ ships it)."),
    ] = False,
    params: Annotated[
        str, typer.Option("--params", "-p", help="Rig parameter set for --cost-table.")
    ] = "thesis-rig",
    repeats: Annotated[int, typer.Option(
        help="--cost-table, --thesis-comparison: timed repeats, 2 to 1000.",
        callback=option_range(Bounds(2, 1000, lower_inclusive=True)))] = 15,
    duration: Annotated[
        float, typer.Option(help="--cost-table: simulated time per run [s], 0.1 to 3600.",
                            callback=option_range(Bounds(0.1, MAX_SIMULATED_TIME, "s",
                                                         lower_inclusive=True)),
                            parser=number_in("s"), metavar="QUANTITY")
    ] = 4.0,
) -> None:
    """Write report.html (self-contained, figures embedded) and the PNGs of a run folder,
    optionally compared with a measured recording; or, with --cost-table, the thesis's
    Table 3 measured on this machine."""
    if cost_table:
        _cost_table(output or Path("runs/cost-table"), params, repeats, duration)
        return
    if thesis_comparison:
        _thesis_comparison(output or Path("runs/thesis-comparison"), repeats)
        return
    if run is None:
        _fail(ValueError("give a run folder, or --cost-table"))
    from pneumaquad.reporting.report import build_run_report

    try:
        with progress_bar("report") as update:
            path = build_run_report(run, output, measured, mapping, time_offset, update,
                                    units)
    except REPORT_ERRORS as error:
        _fail(error)
    if measured is not None:
        from pneumaquad.reporting.sections import COMPARISON_NAME

        _print_comparison(path.parent / COMPARISON_NAME, units)
    console.print(f"report: [bold]{path}[/bold]", soft_wrap=True)


def _print_comparison(path: Path, system: str) -> None:
    """The simulated-against-measured figures of ``comparison.json`` (SI), one row a
    signal, in the report's units."""
    from rich.markup import escape
    from rich.table import Table

    from pneumaquad.io.run_folder import read_json
    from pneumaquad.reporting.display_units import display_units

    if not path.is_file():
        return
    units = display_units(system)
    rows = read_json(path).get("signals", [])
    table = Table(title="simulated against measured")
    for header in ("signal", "unit", "RMSE", "RMSE [% of range]", "largest error", "lag [s]"):
        table.add_column(escape(header), justify="left" if header == "signal" else "right")
    for row in rows:  # units in brackets are text, not markup
        name, _, si_unit = row["signal"].rpartition(" [")
        rmse, unit = units.error(row["rmse"], si_unit.rstrip("]"))
        largest, _ = units.error(row["max_abs_error"], si_unit.rstrip("]"))
        table.add_row(escape(name), escape(unit), f"{rmse:.4g}", f"{row['rmse_percent']:.3g}",
                      f"{largest:.4g}", f"{row['lag']:+.4f}")
    console.print(table)


def _cost_table(output: Path, params: str, repeats: int, duration: float) -> None:
    from pneumaquad.reporting.cost_report import cost_table_markdown, write_cost_table_report
    from pneumaquad.reporting.cost_table import measure_cost_table

    try:
        with progress_bar("cost table") as update:
            table = measure_cost_table(params, duration, repeats, progress=update)
        path = write_cost_table_report(table, output)
    except REPORT_ERRORS as error:
        _fail(error)
    typer.echo(cost_table_markdown(table))
    console.print(f"report: [bold]{path}[/bold]", soft_wrap=True)


def _thesis_comparison(output: Path, repeats: int) -> None:
    from pneumaquad.validation.comparison import measure_comparison
    from pneumaquad.validation.comparison_page import write_comparison_page

    try:
        with progress_bar("thesis comparison") as update:
            comparison = measure_comparison(repeats, progress=update)
        page = write_comparison_page(comparison, output)
    except REPORT_ERRORS as error:
        _fail(error)
    console.print(f"page: [bold]{page}[/bold]", soft_wrap=True)
