"""``pneumaquad study``: run a study file and report on its folder (docs/studies.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from pneumaquad.cli.common import command_group, console
from pneumaquad.params import ParameterError, Problem

study_app = command_group(help="Studies: many runs with varied parameters (sweeps, Monte "
                          "Carlo, sensitivity), on all cores or a Ray cluster.",
                          no_args_is_help=True)


@study_app.command("run")
def study_run(
    study: Annotated[Path, typer.Argument(help="Study file (TOML).")],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Study folder (default runs/study-<name>); a folder of the "
        "same study is resumed: its finished cases are skipped.")] = None,
    workers: Annotated[int | None, typer.Option(
        help="Worker processes (default: every CPU this process may use); 1 runs the "
        "cases in this process.")] = None,
    ray: Annotated[str | None, typer.Option(
        "--ray", help='Run on Ray: "local" starts a local cluster of --workers CPUs, or the '
        "address of a running cluster (needs Ray: pip install 'pneumaquad\\[cluster]').")] = None,
    limit: Annotated[int | None, typer.Option(
        help="Run at most this many of the missing cases (try a study).")] = None,
) -> None:
    """Run the cases of a study the folder does not hold yet; each case's row is kept as
    it ends, failures included (docs/studies.md). Report: pneumaquad study report DIR."""
    from pneumaquad.studies import (
        StudyProgress,
        default_workers,
        load_study,
        pool_executor,
        ray_executor,
        run_study,
        serial_executor,
    )

    spec = load_study(study)
    count = default_workers() if workers is None else workers
    if count < 1:
        raise ParameterError([Problem("--workers", count, "should be at least 1")])
    if limit is not None and limit < 1:
        raise ParameterError([Problem("--limit", limit, "should be at least 1")])
    if ray is not None:
        executor = ray_executor(ray, count)
    else:
        executor = serial_executor if count == 1 else pool_executor(count)
    folder = output if output is not None else Path("runs") / f"study-{spec.name}"
    result = run_study(spec, folder, executor, StudyProgress(spec.name, spec.cases),
                       limit)
    where = "this process" if ray is None and count == 1 else (
        f"Ray ({ray})" if ray is not None else f"{count} worker processes")
    console.print(f"study {spec.name}: {result.ran} cases run on {where} in "
                  f"{result.wall_time:.1f} s ({result.cases_per_second:.3g} cases/s), "
                  f"{result.skipped} recorded before; {result.failed} failed in all; "
                  f"folder [bold]{folder}[/bold]", highlight=False)
    if result.stopped:
        console.print("stopped: run the same command again to finish the study")
        raise typer.Exit(130)


@study_app.command("report")
def study_report(
    folder: Annotated[Path, typer.Argument(help="Study folder (from study run).")],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Report file (default DIR/report.html).")] = None,
) -> None:
    """HTML report of a study folder: distributions of every metric, scatter plots against
    the varied parameters, a sensitivity table, and the failed cases with the command that
    repeats each."""
    from pneumaquad.studies.report import write_study_report

    path = write_study_report(folder, output)
    console.print(f"report: [bold]{path}[/bold]")
