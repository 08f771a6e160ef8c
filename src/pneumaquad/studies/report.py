"""The HTML report of a study folder (``pneumaquad study report DIR``).

One self-contained page (:class:`pneumaquad.reporting.html.HtmlPage`): the study and its
varied parameters; per metric its spread (quantiles), its histogram and box plot and its
scatter against every numeric varied parameter; the cases as parallel coordinates; the
sensitivity table (:mod:`.sensitivity`) when the design was sampled; how the runs went (a
walk's reasons, counted); and every failed case with its error and the one command that
repeats it alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pneumaquad.params.errors import ParameterError, Problem
from pneumaquad.reporting.html import HtmlPage

from .plots import distribution_png, parallel_png, scatter_png
from .results import read_results, study_of
from .run_options import reproduce_command
from .sampling import study_cases
from .sensitivity import MIN_CASES, sensitivity_table, sobol_indices
from .spec import StudySpec, VariedParameter

__all__ = ["REPORT_NAME", "write_study_report"]

REPORT_NAME = "report.html"
#: Failed cases listed in full in the report (the rest are counted).
MAX_LISTED_FAILURES = 200


def _describe(parameter: VariedParameter) -> str:
    if parameter.values is not None:
        shown = ", ".join(f"{v:g}" if isinstance(v, float) else str(v)
                          for v in parameter.values)
        return f"values {shown}"
    distribution = parameter.distribution
    numbers = ", ".join(f"{n:g}" for n in distribution.numbers if np.isfinite(n))
    return f"{distribution.kind} ({numbers})"


def _study_section(page: HtmlPage, spec: StudySpec, ok: int, failed: int,
                   wall: float) -> None:
    run = spec.run
    if spec.description:
        page.paragraph(spec.description)
    options = ", ".join(f"{k} = {v}" for k, v in run.options.items())
    page.table(["", ""], [
        ["base run", f"{run.kind} with {run.params}" + (f" ({options})" if options else "")],
        ["fixed overrides", "; ".join(run.overrides) or "none"],
        ["sampling", f"{spec.sampling}, {spec.cases} cases, seed {spec.seed}"],
        ["cases recorded", f"{ok + failed} of {spec.cases}: {ok} ok, {failed} failed"],
        ["case wall time, summed [s]", wall],
    ])
    page.heading("Varied parameters")
    page.table(["key", "unit", "drawn from"],
               [[p.key, p.unit or "–", _describe(p)] for p in spec.varied])


def _metric_sections(page: HtmlPage, spec: StudySpec, columns: dict[str, np.ndarray],
                     numeric: dict[str, np.ndarray], failed: np.ndarray) -> None:
    page.heading("Metrics")
    rows = []
    for name in spec.metrics:
        values = columns[name][np.isfinite(columns[name])]
        if values.size == 0:
            rows.append([name, 0, *([None] * 5)])
            continue
        rows.append([name, int(values.size), *np.percentile(values, [5, 25, 50, 75, 95])])
    page.table(["metric", "finite cases", "5 %", "25 %", "median", "75 %", "95 %"], rows)
    for name in spec.metrics:
        values = columns[name]
        if not np.isfinite(values).any():
            page.paragraph(f"{name}: no finite value in any case.", note=True)
            continue
        page.heading(name, level=3)
        page.figure(distribution_png(name, values), f"{name}: histogram and box plot")
        if numeric:
            page.figure(scatter_png(name, values, numeric, failed),
                        f"{name} against the varied parameters")


def _grid_tables(page: HtmlPage, spec: StudySpec, columns: dict[str, np.ndarray]) -> None:
    """A grid of two keys: each metric as a table, the first key down, the second across
    (a failed case is a blank cell)."""
    if spec.sampling != "grid" or len(spec.varied) != 2:
        return
    rows_key, columns_key = spec.varied
    page.heading(f"Grid: {rows_key.column} down, {columns_key.column} across")
    down, across = columns[rows_key.column], columns[columns_key.column]

    def stored(parameter: VariedParameter, value: object) -> object:
        return value if parameter.is_number else str(value)  # a choice is stored as text

    for name in spec.metrics:
        page.heading(name, level=3)
        rows = []
        for row_value in rows_key.values:
            cells = []
            for column_value in columns_key.values:
                found = ((down == stored(rows_key, row_value))
                         & (across == stored(columns_key, column_value)))
                cells.append(float(columns[name][found][0]) if found.any() else None)
            rows.append([row_value, *cells])
        page.table([rows_key.column, *(str(v) for v in columns_key.values)], rows)


def _sensitivity_section(page: HtmlPage, spec: StudySpec, columns: dict[str, np.ndarray],
                         numeric: dict[str, np.ndarray]) -> None:
    page.heading("Sensitivity")
    if spec.sampling == "saltelli":
        _sobol_section(page, spec, columns)
        return
    if spec.sampling not in ("latin-hypercube", "sobol") or not numeric:
        page.paragraph(f"No sensitivity table: a {spec.sampling} design is not a random "
                       "sample of the parameters (sample them by latin-hypercube or sobol).",
                       note=True)
        return
    rows = sensitivity_table(numeric, {name: columns[name] for name in spec.metrics},
                             spec.seed)
    if not rows:
        page.paragraph(f"No metric has {MIN_CASES} finite cases with a spread.", note=True)
        return
    page.paragraph("Borgonovo's delta (how much knowing the parameter shifts the metric's "
                   "distribution) and the first-order Sobol index S1 (the share of the "
                   "metric's variance it explains alone), from the cases as sampled, "
                   "through SALib; ± the half-width of the 95 % bootstrap interval.",
                   note=True)
    page.table(["metric", "parameter", "delta", "± delta", "S1", "± S1"],
               [[r.metric, r.parameter, r.delta, r.delta_confidence, r.first_order,
                 r.first_order_confidence] for r in rows], digits=3)


def _notes_section(page: HtmlPage, notes: np.ndarray, failed: np.ndarray) -> None:
    """How the recorded runs went (a walk's reasons): each distinct note and its count."""
    counted: dict[str, int] = {}
    for note in notes[~failed]:
        if note:
            counted[str(note)] = counted.get(str(note), 0) + 1
    if not counted:
        return
    page.heading("How the runs went")
    page.table(["note", "cases"], sorted(counted.items(), key=lambda item: -item[1]))


def _sobol_section(page: HtmlPage, spec: StudySpec, columns: dict[str, np.ndarray]) -> None:
    """Sobol indices of a Saltelli design (every case of it is needed)."""
    if len(columns["case"]) != spec.cases:
        page.paragraph(f"No Sobol indices yet: {len(columns['case'])} of the {spec.cases} "
                       "cases of the Saltelli design are recorded.", note=True)
        return
    rows, skipped = sobol_indices([p.column for p in spec.varied],
                                  {name: columns[name] for name in spec.metrics}, spec.seed)
    page.paragraph("Sobol indices from the Saltelli design, through SALib: S1 the share "
                   "of the metric's variance the parameter explains alone, ST with every "
                   "interaction it takes part in; ± the half-width of the 95 % bootstrap "
                   "interval.", note=True)
    page.table(["metric", "parameter", "S1", "± S1", "ST", "± ST"],
               [[r.metric, r.parameter, r.first_order, r.first_order_confidence, r.total,
                 r.total_confidence] for r in rows], digits=3)
    if skipped:
        page.paragraph("Left out (a failed or non-finite case, or no spread): "
                       + ", ".join(skipped) + ".", note=True)


def _failures_section(page: HtmlPage, spec: StudySpec, cases: list[int],
                      errors: list[str]) -> None:
    page.heading("Failed cases")
    if not cases:
        page.paragraph("None.")
        return
    by_index = {case.index: case for case in study_cases(spec)}
    rows = []
    for index, error in list(zip(cases, errors, strict=True))[:MAX_LISTED_FAILURES]:
        case = by_index[index]
        command = reproduce_command(spec.run, case.overrides, case.run_options, case.seed)
        rows.append([index, error, command])
    page.table(["case", "error", "command that repeats it"], rows)
    if len(cases) > MAX_LISTED_FAILURES:
        page.paragraph(f"{len(cases) - MAX_LISTED_FAILURES} more failed cases are in the "
                       "table (status failed).", note=True)


def write_study_report(folder: Path, output: Path | None = None) -> Path:
    """Write the report of a study folder; returns its path (default
    ``DIR/report.html``).

    Raises
    ------
    ParameterError
        ``folder`` is not a study folder or holds no finished case.
    """
    folder = Path(folder)
    table = read_results(folder)
    if table is None:
        raise ParameterError([Problem("DIR", str(folder), "holds no finished case yet; run "
                                      "pneumaquad study run first")])
    spec = study_of(folder)
    columns = {name: table.column(name).to_numpy(zero_copy_only=False)
               for name in table.column_names}
    status = columns["status"]
    failed = status != "ok"
    numeric = {p.column: columns[p.column].astype(float) for p in spec.varied if p.is_number}
    page = HtmlPage(f"Study {spec.name}")
    _study_section(page, spec, int((~failed).sum()), int(failed.sum()),
                   float(np.nansum(columns["wall time [s]"])))
    _metric_sections(page, spec, columns, numeric, failed)
    if numeric and spec.metrics:
        page.heading("Cases as parallel coordinates")
        lines = {**numeric, **{name: columns[name] for name in spec.metrics}}
        if np.all(np.isfinite(np.column_stack(list(lines.values()))), axis=1).any():
            page.figure(parallel_png(lines, spec.metrics[0]),
                        "each line a case; every axis scaled to its own range")
    _grid_tables(page, spec, columns)
    _sensitivity_section(page, spec, columns, numeric)
    _notes_section(page, columns["note"], failed)
    _failures_section(page, spec, [int(i) for i in columns["case"][failed]],
                      [str(e) for e in columns["error"][failed]])
    return page.write(output if output is not None else folder / REPORT_NAME)
