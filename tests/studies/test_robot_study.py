"""A robot study: each case builds the quadruped, stands it up and reads its summary; a
supply too low to lift it is refused and recorded, and the study goes on."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pneumaquad.studies import parse_study, read_results, run_study, serial_executor

STAND_STUDY = """
[study]
name = "stand-2"
sampling = "list"
metrics = ["checks.stance check.verified", "checks.stance check.thorax height [m]",
           "phases.stand up.air consumed [NL]"]
keep_runs = true

[run]
kind = "robot-stand"
hold = "1 s"
posture = false

[vary."actuators.supply_pressure"]
values = ["50.3 psig", "5 psig"]
"""


def test_a_stand_study_records_each_case_and_keeps_its_run(tmp_path: Path) -> None:
    spec = parse_study(STAND_STUDY)
    result = run_study(spec, tmp_path / "study", serial_executor)
    table = read_results(tmp_path / "study").to_pydict()
    assert result.ran == 2
    assert table["status"] == ["ok", "failed"]
    assert table["checks.stance check.verified"][0] == 1.0
    assert 0.2 < table["checks.stance check.thorax height [m]"][0] < 0.6
    assert table["phases.stand up.air consumed [NL]"][0] > 0
    assert "supply" in table["error"][1]
    assert np.isnan(table["checks.stance check.thorax height [m]"][1])
    kept = Path(table["run folder"][0])
    assert kept.parent == tmp_path / "study" / "runs" and (kept / "summary.json").is_file()


def test_a_case_gives_the_same_figures_whether_its_run_is_kept_or_not(tmp_path: Path) -> None:
    """A case whose run folder is not kept writes it as scratch (Parquet only, no plots)
    and removes it; its figures are those of the same case kept, bit for bit, and the kept
    folder has its CSV recording."""
    kept_spec = parse_study(STAND_STUDY.replace('values = ["50.3 psig", "5 psig"]',
                                                'values = ["50.3 psig"]'))
    scratch_spec = parse_study(STAND_STUDY.replace('values = ["50.3 psig", "5 psig"]',
                                                   'values = ["50.3 psig"]')
                               .replace("keep_runs = true", "keep_runs = false"))
    run_study(kept_spec, tmp_path / "kept", serial_executor)
    run_study(scratch_spec, tmp_path / "scratch", serial_executor)
    kept = read_results(tmp_path / "kept").to_pydict()
    scratch = read_results(tmp_path / "scratch").to_pydict()
    for metric in kept_spec.metrics:
        assert kept[metric] == scratch[metric], metric
    assert scratch["run folder"] == [""]
    assert (Path(kept["run folder"][0]) / "recording.csv").is_file()
