"""The run report: one self-contained ``report.html`` (figures embedded) plus the PNGs.

:func:`build_run_report` is the entry point of ``pneumaquad report``;
:func:`write_run_report` does the work on already loaded inputs.
"""

from __future__ import annotations

import datetime
from collections.abc import Callable
from pathlib import Path

import numpy as np

from pneumaquad.io.measured import load_mapping, read_measured
from pneumaquad.params import RigSetup

from .comparison import compare_with_measured
from .display_units import DisplayUnits, display_units
from .html import HtmlPage
from .run_folder import LoadedRun, ReportError, load_run_folder
from .sections import (
    add_comparison,
    add_model_curves,
    add_network_timing,
    add_parameters,
    add_summary,
    add_time_histories,
)

__all__ = ["REPORT_NAME", "build_run_report", "write_run_report"]

REPORT_NAME = "report.html"
Progress = Callable[[int, int], None]


def write_run_report(
    run: LoadedRun,
    folder: Path,
    measured: dict[str, np.ndarray] | None = None,
    measured_source: str = "",
    time_offset: float = 0.0,
    progress: Progress | None = None,
    units: str | DisplayUnits = "si",
) -> Path:
    """Write ``report.html`` and its PNGs for a loaded run.

    Parameters
    ----------
    run : LoadedRun
        The loaded run.
    folder : Path
        Report folder (created).
    measured : dict of str to numpy.ndarray, optional
        A measured recording in SI (from :func:`pneumaquad.io.measured.read_measured`); rig
        runs only.
    measured_source : str
        Where the measured data came from, for the page.
    time_offset : float
        Added to the measured time stamps [s].
    progress : callable, optional
        Called with (sections done, sections total).
    units : str or DisplayUnits
        Units of every figure, table and text: ``"si"`` (default) or ``"us"`` (the
        thesis's in, psi, lbf); see :mod:`pneumaquad.reporting.display_units`.

    Returns
    -------
    Path
        The written ``report.html``.

    Raises
    ------
    ReportError
        For measured data with a robot run, or measured data that cannot be compared.
    ValueError
        For an unknown unit system.
    """
    shown = display_units(units)
    if measured is not None and not isinstance(run.parameters, RigSetup):
        raise ReportError(
            "comparison with measured data is available for rig runs only; "
            f"{run.path} is a robot run"
        )
    folder = Path(folder)
    page = HtmlPage(f"pneumaquad run report: {run.description}")
    interrupted = (
        " It was interrupted (Ctrl-C): the recording holds the part that ran."
        if run.summary.get("interrupted")
        else ""
    )
    page.paragraph(
        f"Run folder {run.path} ({run.kind} run, parameter set {run.set_name}); "
        f"report written {datetime.datetime.now().isoformat(timespec='seconds')} in "
        f"{shown.description}.{interrupted}"
    )
    for note in run.notes:
        page.paragraph(note, note=True)
    steps: list[Callable[[], None]] = [
        lambda: add_parameters(page, run, shown),
        lambda: add_summary(page, run, shown),
        lambda: add_time_histories(page, run, folder, shown),
        lambda: add_model_curves(page, run, folder, shown),
        lambda: add_network_timing(page, run, shown),
    ]
    if measured is not None:
        assert isinstance(run.parameters, RigSetup)
        stroke = run.parameters.actuator.cylinder.stroke
        # compared first, so that data that cannot be compared fails before any file
        result = compare_with_measured(run.recording, measured, stroke, time_offset)
        steps.append(lambda: add_comparison(page, run, result, measured, measured_source, folder,
                                            shown))
    folder.mkdir(parents=True, exist_ok=True)
    for index, step in enumerate(steps):
        step()
        if progress is not None:
            progress(index + 1, len(steps))
    return page.write(folder / REPORT_NAME)


def build_run_report(
    run: Path,
    output: Path | None = None,
    measured: Path | None = None,
    mapping: Path | None = None,
    time_offset: float = 0.0,
    progress: Progress | None = None,
    units: str | DisplayUnits = "si",
) -> Path:
    """Load a run folder (and measured data) and write its report.

    Parameters
    ----------
    run : Path
        Run folder of a rig or robot experiment.
    output : Path, optional
        Report folder; default ``<run>/report``.
    measured, mapping : Path, optional
        Measured recording (CSV/MAT) and its TOML column mapping; both or neither.
    time_offset : float
        Added to the measured time stamps [s].
    progress : callable, optional
        Called with (sections done, sections total).
    units : str or DisplayUnits
        ``"si"`` (default) or ``"us"``: see :func:`write_run_report`.

    Returns
    -------
    Path
        The written ``report.html``.

    Raises
    ------
    ReportError, ParameterError, MeasuredDataError
        For a missing or malformed run folder, parameter file or measured data.
    ValueError
        For an unknown unit system.
    """
    display_units(units)  # an unknown system fails before anything is read
    if (measured is None) != (mapping is None):
        raise ReportError("--measured and --mapping go together: give both or neither")
    loaded = load_run_folder(run)
    recording = None
    if measured is not None and mapping is not None:
        if loaded.kind != "rig":
            raise ReportError(
                "comparison with measured data is available for rig runs "
                f"only; {loaded.path} is a robot run"
            )
        recording = read_measured(measured, load_mapping(mapping))
    folder = Path(output) if output is not None else loaded.path / "report"
    return write_run_report(loaded, folder, recording, str(measured or ""), time_offset, progress,
                            units)
