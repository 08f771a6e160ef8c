"""The same study on a local Ray cluster gives the table of one process (skipped where Ray
is not installed: pip install 'pneumaquad[cluster]')."""

from __future__ import annotations

from pathlib import Path

import pytest
from study_files import FRICTION_STUDY

from pneumaquad.studies import parse_study, ray_executor, read_results, run_study, serial_executor

pytest.importorskip("ray")


@pytest.mark.slow  # starting a Ray cluster takes longer than the default suite's tests
def test_ray_gives_the_table_of_one_process(tmp_path: Path) -> None:
    spec = parse_study(FRICTION_STUDY)
    run_study(spec, tmp_path / "serial", serial_executor)
    on_ray = run_study(spec, tmp_path / "ray", ray_executor("local", 2))
    assert on_ray.ran == 8
    columns = ["wall time [s]"]
    assert read_results(tmp_path / "ray").drop_columns(columns).equals(
        read_results(tmp_path / "serial").drop_columns(columns))
