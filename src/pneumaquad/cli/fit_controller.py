"""Command line for controller identification: ``pneumaquad fit controller``.

A thin layer over `pneumaquad.identification.fit_controller`, registered on the ``fit``
command group (`pneumaquad.cli.fit`) with the same inputs (run folders, recording files,
measured files with a column mapping that maps the reference position), the same output
(a parameter file ``--params`` accepts) and the same exit statuses: 2 for unusable input,
1 for a fit that failed its checks (nothing written unless ``--force``).
"""

from __future__ import annotations

from typing import Annotated

import typer

from pneumaquad.cli.common import ParamsOption, SetOption, console, stderr_console
from pneumaquad.cli.fit import (
    ForceOption,
    MappingOption,
    OutputOption,
    RecordingsArgument,
    expand_paths,
    read_input,
    refuse_failed_fits,
    show_fit,
    user_errors,
)
from pneumaquad.identification.controller_data import METHODS, START_STATES, ControllerFit
from pneumaquad.identification.report import write_parameter_file
from pneumaquad.io.measured import load_mapping
from pneumaquad.params import ParameterError, load_rig, parse_quantity
from pneumaquad.params.schema import MAX_MEASUREMENT_DELAY

__all__ = ["fit_controller_command"]

#: ``--filter`` choices: fit the derivative filter where the data determine it, or hold
#: the parameter set's.
FILTER_CHOICES = ("fit", "params")
#: ``--offset`` choices: the parameter set's valve offset, or fitted (command method).
OFFSET_CHOICES = ("params", "fit")


def _choice(text: str, choices: tuple[str, ...], option: str) -> str:
    value = text.strip().lower()
    if value not in choices:
        raise ParameterError.single(option, text, " or ".join(choices))
    return value


def _delay_option(text: str, option: str) -> float | None:
    """``auto`` (None) or a time within [0, 0.1 s] [s]."""
    if option == "--delay" and text.strip().lower() == "auto":
        return None
    value = parse_quantity(text, "time", option)
    if not 0.0 <= value <= MAX_MEASUREMENT_DELAY:
        raise ParameterError.single(option, text,
                                    f"a time from 0 s to {MAX_MEASUREMENT_DELAY:g} s")
    return value


def show_controller(fit: ControllerFit) -> None:
    """Print the method, the fit table, the filter, lag and delay, and the fit's notes."""
    console.print(f"method: {fit.method}", highlight=False)
    show_fit(fit.fit)
    source = "fitted" if fit.filter_fitted else "held at the parameter set's value"
    console.print(f"  derivative filter: {fit.filter_time_constant * 1e3:.4g} ms ({source})",
                  highlight=False)
    searched = "searched" if fit.delay_fitted else "given"
    console.print(
        f"  measurement delay: {fit.measurement_delay * 1e3:.4g} ms ({searched}; lag from "
        f"position to command {fit.lag * 1e3:.4g} ms, control step "
        f"{fit.control_step * 1e3:.4g} ms, sample period {fit.sample_period * 1e3:.4g} ms)",
        highlight=False)
    for note in fit.notes:
        console.print("  note:", style="yellow", end=" ")
        console.print(note, highlight=False, markup=False, soft_wrap=True)


def fit_controller_command(
    recordings: RecordingsArgument,
    output: OutputOption,
    params: ParamsOption = "thesis-rig",
    overrides: SetOption = None,
    mapping: MappingOption = None,
    method: Annotated[
        str, typer.Option(help="auto (command if every recording has the valve command, "
                          "else output-error), command, or output-error.")
    ] = "auto",
    filter_: Annotated[
        str, typer.Option("--filter", help="fit the derivative filter time constant where "
                          "the data determine it, or hold the parameter set's (params).")
    ] = "fit",
    delay: Annotated[
        str, typer.Option(help='Measurement delay: auto (searched) or a time such as "10 ms".')
    ] = "auto",
    max_delay: Annotated[str, typer.Option(help="Longest delay searched.")] = "50 ms",
    offset: Annotated[
        str, typer.Option(help="Valve offset of the command method: the parameter set's "
                          "(params) or fitted (fit; it then also takes up an integral that "
                          "was not zero when the recording began).")
    ] = "params",
    start: Annotated[
        str, typer.Option(help="Start state of the output-error simulation: auto, parameters "
                          "(the set's rig.initial_*), or recording (at rest at its first row).")
    ] = "auto",
    force: ForceOption = False,
) -> None:
    """PID gains, derivative filter and loop delay from closed-loop recordings.

    The recordings need time, reference position and position; with the valve command the
    PID is fitted to it directly (no plant model needed), else the rig of --params is
    simulated in closed loop and the gains fitted to the position. The parameter file
    written is --params with the controller's gains (and the filter and delay where
    fitted).
    """
    with user_errors():
        setup = load_rig(params, overrides or [])
        chosen = _choice(method, METHODS, "--method")
        fit_filter = _choice(filter_, FILTER_CHOICES, "--filter") == "fit"
        fit_offset = _choice(offset, OFFSET_CHOICES, "--offset") == "fit"
        state = _choice(start, START_STATES, "--start")
        assumed = _delay_option(delay, "--delay")
        longest = _delay_option(max_delay, "--max-delay")
        column_mapping = load_mapping(mapping) if mapping is not None else None
        paths = expand_paths(recordings, "RECORDINGS")
        data = [read_input(path, column_mapping) for path in paths]

        def progress(line: str) -> None:
            stderr_console.print(f"  {line}", style="dim", highlight=False)

        from pneumaquad.identification.controller import fit_controller

        fit = fit_controller(
            data, setup, method=chosen, fit_filter=fit_filter, delay=assumed,
            max_delay=longest, fit_offset=fit_offset, start=state,
            labels=[str(path) for path in paths], progress=progress)
        show_controller(fit)
        refuse_failed_fits((fit.fit,), force)
        written = write_parameter_file(params, fit.updates(), output, fits=(fit.fit,),
                                       overrides=overrides or [])
    console.print(f"parameters: [bold]{written}[/bold]")
