"""A study's folder: its spec, and its cases as a Parquet dataset that survives a kill.

Layout (docs/studies.md)::

    DIR/study.toml            the spec the study runs (a rerun must match it)
    DIR/cases/part-*.parquet  finished cases, one file per finished batch, written
                              whole then renamed into place, so a kill loses at most the
                              batches that were running
    DIR/results.parquet       every finished case in case order, written when a run ends
                              (the parts are then removed)
    DIR/runs/case-NNNNNN/     robot run folders, when the spec keeps them

A table has one row per case: ``case``, ``seed``, one column per varied key (numbers in
the key's unit, named ``"key [unit]"``; texts for a choice), ``status`` (``"ok"`` or
``"failed"``), ``error``, ``wall time [s]``, ``run folder``, ``note`` (how a robot run
went: a walk's reasons), then one column per metric (its summary name, SI units as the
summary gives them).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from pneumaquad.params.errors import ParameterError, Problem

from .case_runs import CaseOutcome
from .sampling import Case
from .spec import StudySpec, load_study

__all__ = ["PARTS_FOLDER", "RESULTS_NAME", "RUNS_FOLDER", "SPEC_NAME", "ResultStore",
           "read_results", "results_schema"]

SPEC_NAME = "study.toml"
RESULTS_NAME = "results.parquet"
PARTS_FOLDER = "cases"
RUNS_FOLDER = "runs"
#: Columns every study table has besides its parameters and metrics.
FIXED_COLUMNS = ("case", "seed", "status", "error", "wall time [s]", "run folder", "note")


def results_schema(spec: StudySpec) -> pa.Schema:
    """The columns of a study's table (module docstring)."""
    fields = [pa.field("case", pa.int64()), pa.field("seed", pa.int64())]
    fields += [pa.field(p.column, pa.float64() if p.is_number else pa.string())
               for p in spec.varied]
    fields += [pa.field("status", pa.string()), pa.field("error", pa.string()),
               pa.field("wall time [s]", pa.float64()), pa.field("run folder", pa.string()),
               pa.field("note", pa.string())]
    fields += [pa.field(name, pa.float64()) for name in spec.metrics]
    return pa.schema(fields)


def _rows(spec: StudySpec, cases: Sequence[Case], outcomes: Sequence[CaseOutcome]) -> pa.Table:
    by_index = {case.index: case for case in cases}
    columns: dict[str, list] = {name: [] for name in results_schema(spec).names}
    for outcome in outcomes:
        case = by_index[outcome.index]
        columns["case"].append(case.index)
        columns["seed"].append(case.seed)
        for parameter, value in zip(spec.varied, case.values, strict=True):
            columns[parameter.column].append(value if parameter.is_number else str(value))
        columns["status"].append(outcome.status)
        columns["error"].append(outcome.error)
        columns["wall time [s]"].append(outcome.wall_time)
        columns["run folder"].append(outcome.run_folder)
        columns["note"].append(outcome.note)
        for name in spec.metrics:
            columns[name].append(outcome.metrics.get(name, float("nan")))
    return pa.table(columns, schema=results_schema(spec))


def _write_atomically(table: pa.Table, path: Path) -> None:
    partial = path.with_name(f".{path.name}.partial")
    pq.write_table(table, partial)
    os.replace(partial, path)


class ResultStore:
    """The writer of a study folder (module docstring): one per running study.

    Parameters
    ----------
    folder : Path
        The study folder; created if missing.
    spec : StudySpec

    Raises
    ------
    ParameterError
        When the folder already holds another study (its ``study.toml`` differs).
    """

    def __init__(self, folder: Path, spec: StudySpec) -> None:
        self.folder = Path(folder)
        self.spec = spec
        spec_file = self.folder / SPEC_NAME
        if spec_file.exists() and spec_file.read_text(encoding="utf-8") != spec.text:
            raise ParameterError([Problem("--output", str(self.folder), "holds another study "
                                          f"(its {SPEC_NAME} differs); give another folder")])
        (self.folder / PARTS_FOLDER).mkdir(parents=True, exist_ok=True)
        if not spec_file.exists():
            spec_file.write_text(spec.text, encoding="utf-8")

    def finished(self) -> set[int]:
        """Indices of the cases already recorded (ok or failed)."""
        table = read_results(self.folder, columns=["case"])
        return set(table.column("case").to_pylist()) if table is not None else set()

    def append(self, cases: Sequence[Case], outcomes: Sequence[CaseOutcome]) -> None:
        """Record finished cases: one part file, in place only once written whole."""
        if not outcomes:
            return
        table = _rows(self.spec, cases, outcomes)
        first = min(outcome.index for outcome in outcomes)
        name = f"part-{first:07d}-{len(outcomes)}.parquet"
        _write_atomically(table, self.folder / PARTS_FOLDER / name)

    def consolidate(self) -> Path:
        """Write ``results.parquet`` (every case so far, in case order, each once) and
        remove the parts it holds."""
        parts = sorted((self.folder / PARTS_FOLDER).glob("part-*.parquet"))
        table = read_results(self.folder)
        target = self.folder / RESULTS_NAME
        if table is None:
            table = results_schema(self.spec).empty_table()
        _write_atomically(table, target)
        for part in parts:
            part.unlink()
        return target


def read_results(folder: Path, columns: list[str] | None = None) -> pa.Table | None:
    """A study folder's cases so far (``results.parquet`` and the parts), one row per case
    in case order; None when none has finished.

    Raises
    ------
    ParameterError
        When ``folder`` holds no ``study.toml``.
    """
    folder = Path(folder)
    if not (folder / SPEC_NAME).is_file():
        raise ParameterError([Problem("DIR", str(folder), f"is not a study folder (no "
                                      f"{SPEC_NAME})")])
    files = [folder / RESULTS_NAME] if (folder / RESULTS_NAME).is_file() else []
    files += sorted((folder / PARTS_FOLDER).glob("part-*.parquet"))
    if not files:
        return None
    read = None if columns is None else ["case", *(c for c in columns if c != "case")]
    table = pa.concat_tables([pq.read_table(file, columns=read) for file in files])
    if table.num_rows == 0:
        return None
    order = pc.sort_indices(table, sort_keys=[("case", "ascending")])
    table = table.take(order)
    cases = table.column("case").to_numpy()
    keep = [0, *[i for i in range(1, len(cases)) if cases[i] != cases[i - 1]]]
    return table.take(keep) if len(keep) < table.num_rows else table


def study_of(folder: Path) -> StudySpec:
    """The spec a study folder was run with."""
    return load_study(Path(folder) / SPEC_NAME)
