"""A study runs the same on every executor, resumes where it stopped, and records a failing
or diverging case without stopping."""

from __future__ import annotations

import dataclasses
import shlex
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from study_files import FRICTION_STUDY
from typer.testing import CliRunner

from pneumaquad.cli.main import app
from pneumaquad.params import ParameterError, load_rig
from pneumaquad.rig.simulate import RigDivergedError
from pneumaquad.studies import (
    case_runs,
    load_study,
    parse_study,
    pool_executor,
    read_results,
    run_study,
    serial_executor,
    study_cases,
)
from pneumaquad.studies.report import write_study_report
from pneumaquad.studies.run_options import reproduce_command


def _without_wall_time(table: pa.Table) -> pa.Table:
    return table.drop_columns(["wall time [s]"])


def test_the_pool_gives_the_table_of_one_process_case_by_case(tmp_path: Path) -> None:
    spec = parse_study(FRICTION_STUDY)
    alone = dataclasses.replace(spec, batch=1)  # every rig alone, in this process
    run_study(alone, tmp_path / "serial", serial_executor)
    pooled = run_study(spec, tmp_path / "pool", pool_executor(2))
    assert pooled.ran == 8 and pooled.failed == 0
    serial_table = _without_wall_time(read_results(tmp_path / "serial"))
    pool_table = _without_wall_time(read_results(tmp_path / "pool"))
    assert pool_table.equals(serial_table)
    rise = pool_table.column("rise time 10-90 % [s]").to_numpy()
    assert np.all(np.isfinite(rise)) and np.ptp(rise) > 0  # the cases differ
    assert pool_table.column("case").to_pylist() == list(range(8))


def _stopping_after(batches: int):
    """An executor that runs ``batches`` batches, then stops as Ctrl-C would."""

    def execute(tasks: Iterable) -> Iterator:
        for count, item in enumerate(serial_executor(tasks)):
            if count == batches:
                raise KeyboardInterrupt
            yield item

    return execute


def test_a_stopped_study_resumes_without_running_finished_cases(tmp_path: Path) -> None:
    spec = parse_study(FRICTION_STUDY)  # batches of 3: cases 0-2, 3-5, 6-7
    first = run_study(spec, tmp_path / "study", _stopping_after(1))
    assert first.stopped and first.ran == 3
    kept = read_results(tmp_path / "study")
    assert kept.column("case").to_pylist() == [0, 1, 2]
    second = run_study(spec, tmp_path / "study", serial_executor)
    assert (second.skipped, second.ran, second.stopped) == (3, 5, False)
    finished = read_results(tmp_path / "study")
    # the first three rows are the ones recorded before the stop (their wall times too)
    assert finished.slice(0, 3).equals(kept)
    run_study(spec, tmp_path / "fresh", serial_executor)
    assert _without_wall_time(finished).equals(_without_wall_time(
        read_results(tmp_path / "fresh")))
    third = run_study(spec, tmp_path / "study", serial_executor)
    assert (third.skipped, third.ran) == (8, 0)


def test_a_folder_of_another_study_is_refused(tmp_path: Path) -> None:
    run_study(parse_study(FRICTION_STUDY), tmp_path / "study", _stopping_after(1))
    other = parse_study(FRICTION_STUDY.replace("seed = 11", "seed = 12"))
    with pytest.raises(ParameterError, match="holds another study"):
        run_study(other, tmp_path / "study")


LIST_STUDY = FRICTION_STUDY.split("[vary.")[0].replace(
    'sampling = "latin-hypercube"\ncases = 8', 'sampling = "list"') + """
[vary."rig.load_mass"]
values = ["0.2 kg", "-1 kg", "0.3 kg", "0.4 kg"]
"""


def test_a_refused_case_is_recorded_and_the_study_goes_on(tmp_path: Path) -> None:
    spec = parse_study(LIST_STUDY)
    result = run_study(spec, tmp_path / "study", serial_executor)
    table = read_results(tmp_path / "study")
    assert result.ran == 4 and result.failed == 1
    assert table.column("status").to_pylist() == ["ok", "failed", "ok", "ok"]
    error = table.column("error").to_pylist()[1]
    assert "rig.load_mass" in error and "-1.0 kg" in error
    assert np.isnan(table.column("rise time 10-90 % [s]").to_numpy()[1])
    assert np.isfinite(table.column("rise time 10-90 % [s]").to_numpy()[[0, 2, 3]]).all()
    # the report lists it with the command that repeats it, and that command fails alike
    report = write_study_report(tmp_path / "study").read_text(encoding="utf-8")
    assert "Failed cases" in report and "rig.load_mass" in report
    case = study_cases(spec)[1]
    command = reproduce_command(spec.run, case.overrides, case.run_options, case.seed)
    words = shlex.split(command)
    assert words[:3] == ["pneumaquad", "rig", "step"]
    repeated = CliRunner().invoke(app, [*words[1:], "--output", str(tmp_path / "repeat")])
    assert isinstance(repeated.exception, ParameterError)
    assert "rig.load_mass" in str(repeated.exception)


def test_a_diverging_rig_in_a_batch_is_recorded_and_the_others_finish(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def load_diverging(name, overrides=()):
        """The case of load -1 kg stands for one that diverges: gravity 1e300 m/s^2 (which
        validation would refuse)."""
        kept = [item for item in overrides if '"-1.0 kg"' not in item]
        setup = load_rig(name, kept)
        if len(kept) < len(overrides):
            setup = setup.model_copy(update={"rig": setup.rig.model_copy(
                update={"gravity": 1e300})})
        return setup

    monkeypatch.setattr(case_runs, "load_rig", load_diverging)
    spec = dataclasses.replace(parse_study(LIST_STUDY), batch=4)
    run_study(spec, tmp_path / "study", serial_executor)
    table = read_results(tmp_path / "study")
    assert table.column("status").to_pylist() == ["ok", "failed", "ok", "ok"]
    assert RigDivergedError.__name__ in table.column("error").to_pylist()[1]
    monkeypatch.undo()
    good = [0, 2, 3]
    alone = dataclasses.replace(spec, batch=1)
    run_study(alone, tmp_path / "alone", serial_executor)
    reference = read_results(tmp_path / "alone").take(good)
    assert _without_wall_time(table.take(good)).equals(_without_wall_time(reference))


def test_the_command_line_runs_and_reports_a_study(tmp_path: Path) -> None:
    study = tmp_path / "friction.toml"
    study.write_text(FRICTION_STUDY, encoding="utf-8")
    runner = CliRunner()
    ran = runner.invoke(app, ["study", "run", str(study), "-o", str(tmp_path / "out"),
                              "--workers", "1", "--limit", "4"])
    assert ran.exit_code == 0, ran.output
    assert read_results(tmp_path / "out").num_rows == 4
    reported = runner.invoke(app, ["study", "report", str(tmp_path / "out")])
    assert reported.exit_code == 0, reported.output
    page = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert "rise time 10-90 % [s]" in page and "data:image/png" in page
    assert load_study(tmp_path / "out" / "study.toml").text == FRICTION_STUDY


GRID_STUDY = FRICTION_STUDY.split("[vary.")[0].replace(
    'sampling = "latin-hypercube"\ncases = 8', 'sampling = "grid"') + """
[vary."friction.static_force"]
values = ["3.5 lbf", "5 lbf"]

[vary."supply.supply_pressure"]
values = ["40 psig", "50.3 psig", "60 psig"]
"""


def test_a_grid_runs_every_combination_and_reports_it_as_a_table(tmp_path: Path) -> None:
    spec = parse_study(GRID_STUDY)
    assert spec.cases == 6
    run_study(spec, tmp_path / "study", serial_executor)
    table = read_results(tmp_path / "study").to_pydict()
    assert list(zip(table["friction.static_force [lbf]"], table["supply.supply_pressure [psig]"],
                    strict=True)) == [(3.5, 40.0), (3.5, 50.3), (3.5, 60.0), (5.0, 40.0),
                                      (5.0, 50.3), (5.0, 60.0)]
    peaks = np.array(table["stiction peak force [N]"])
    assert np.all(peaks[3:] > peaks[:3])  # more static friction, a higher break-away peak
    page = write_study_report(tmp_path / "study").read_text(encoding="utf-8")
    assert "Grid: friction.static_force [lbf] down, supply.supply_pressure [psig] across" in page
    assert "No sensitivity table: a grid design" in page


def test_a_batch_that_fails_as_a_whole_is_recorded_and_the_study_goes_on(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from pneumaquad.studies import executors

    def failing_first_batch(run, metrics, cases, runs_folder=None):
        if cases[0].index == 0:
            raise MemoryError("out of memory")
        return case_runs.run_batch(run, metrics, cases, runs_folder)

    monkeypatch.setattr(executors, "run_batch", failing_first_batch)
    result = run_study(parse_study(FRICTION_STUDY), tmp_path / "study", serial_executor)
    table = read_results(tmp_path / "study").to_pydict()
    assert result.ran == 8 and result.failed == 3
    assert table["status"] == ["failed"] * 3 + ["ok"] * 5
    assert table["error"][0] == "the batch failed: MemoryError: out of memory"


def test_a_saltelli_design_gives_sobol_indices(tmp_path: Path) -> None:
    text = FRICTION_STUDY.replace('sampling = "latin-hypercube"', 'sampling = "saltelli"')
    spec = parse_study(text)
    assert spec.cases == 8 * (2 + 2)  # 8 base points, each with D + 2 = 4 runs
    run_study(spec, tmp_path / "study", serial_executor)
    table = read_results(tmp_path / "study").to_pydict()
    from pneumaquad.studies.sensitivity import sobol_indices

    rows, skipped = sobol_indices([p.column for p in spec.varied],
                                  {"stiction peak force [N]": np.array(
                                      table["stiction peak force [N]"])}, spec.seed)
    assert skipped == []
    total = {row.parameter: row.total for row in rows}
    # the break-away peak is the static friction's, not the load's
    assert total["friction.static_force [lbf]"] > total["rig.load_mass [kg]"]
    page = write_study_report(tmp_path / "study").read_text(encoding="utf-8")
    assert "Sobol indices from the Saltelli design" in page
