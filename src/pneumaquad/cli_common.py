"""Pieces shared by the command-line modules: console, common options, progress bar.

Sub-command modules (``cli_robot``, ``cli_serve``, ...) import from here, never from
:mod:`pneumaquad.cli`, which registers them; so any of them can be imported first.
"""

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from pneumaquad.params import parse_quantity

__all__ = [
    "OutputOption",
    "ParamsOption",
    "SetOption",
    "console",
    "finish_run",
    "progress_bar",
    "quantity",
]

console = Console(stderr=True)

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


@contextmanager
def progress_bar(label: str) -> Iterator:
    """A rich progress bar; yields a callback (done, total)."""
    columns = (
        TextColumn(label),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=console, transient=True) as progress:
        task = progress.add_task(label, total=None)

        def update(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield update


def quantity(text: str, kind: str, option: str) -> float:
    """Parse a command-line quantity such as "0.4 in" to SI (raises ParameterError)."""
    return parse_quantity(text, kind, option)


def finish_run(folder: Path, summary: dict) -> None:
    """Print where a run went and end with 130 if it was interrupted."""
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
    if summary.get("interrupted"):
        console.print("[yellow]interrupted: the recording holds the part that ran[/yellow]")
        raise typer.Exit(130)
