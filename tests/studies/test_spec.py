"""Bad study files are refused before anything runs, naming the key, the value and what
was expected; the command line exits 2 with that message and no traceback."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from study_files import FRICTION_STUDY

from conftest import CLI
from pneumaquad.params import ParameterError
from pneumaquad.studies import parse_study


def _refused(text: str) -> str:
    with pytest.raises(ParameterError) as refused:
        parse_study(text, "bad.toml")
    return str(refused.value)


def test_the_friction_study_is_accepted() -> None:
    spec = parse_study(FRICTION_STUDY)
    assert spec.cases == 8 and [p.column for p in spec.varied] == [
        "friction.static_force [lbf]", "rig.load_mass [kg]"]


@pytest.mark.parametrize(("change", "named"), [
    (('[vary."rig.load_mass"]', '[vary."rig.load_masss"]'), 'vary."rig.load_masss"'),
    (('"0.1 kg", "0.15 kg"', '"0.1 V", "0.15 V"'), "vary.\"rig.load_mass\".quartiles"),
    (('low = "3.5 lbf"', 'low = "3.5 kg"'), "friction.static_force"),
    (('cases = 8', 'cases = 0'), "study.cases"),
    (('sampling = "latin-hypercube"\ncases = 8', 'sampling = "sobol"\ncases = 6'),
     "study.cases"),
    (('"air consumed [NL]"', '"air consumption [NL]"'), "study.metrics"),
    (('voltage = "6.5 V"', 'voltage = "6.5 s"'), "run.voltage"),
    (('step_time = "0.3 s"', 'step_tme = "0.3 s"'), "run.step_tme"),
    (('distribution = "uniform"', 'distribution = "triangular"'),
     'vary."friction.static_force".distribution'),
    (('high = "5.0 lbf"', 'high = "3.0 lbf"'), 'vary."friction.static_force".high'),
    (('kind = "rig-step"', 'kind = "rig-walk"'), "run.kind"),
])
def test_a_bad_spec_names_the_key(change: tuple[str, str], named: str) -> None:
    old, new = change
    assert old in FRICTION_STUDY
    message = _refused(FRICTION_STUDY.replace(old, new))
    assert named in message


def test_a_grid_value_of_the_wrong_kind_names_the_key() -> None:
    text = FRICTION_STUDY.replace('sampling = "latin-hypercube"', 'sampling = "grid"')
    text = text.replace("cases = 8\n", "")
    text = text.split('[vary."friction.static_force"]')[0] + (
        '[vary."supply.supply_pressure"]\nvalues = ["40 psig", "50 kg"]\n')
    message = _refused(text)
    assert 'vary."supply.supply_pressure"' in message and "pressure" in message


def test_the_command_line_refuses_a_bad_spec_without_a_traceback(tmp_path: Path) -> None:
    study = tmp_path / "bad.toml"
    study.write_text(FRICTION_STUDY.replace("rig.load_mass", "rig.load_mas"), encoding="utf-8")
    done = subprocess.run([*CLI, "study", "run", str(study), "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, check=False, timeout=120)
    assert done.returncode == 2
    assert 'vary."rig.load_mas"' in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_a_walk_setting_out_of_range_names_the_option() -> None:
    walk = Path(__file__).resolve().parents[2] / "studies" / "walking-robustness.toml"
    text = walk.read_text(encoding="utf-8")
    assert 'distance = "0.3 m"' in text
    parse_study(text)
    message = _refused(text.replace('distance = "0.3 m"', 'distance = "300 m"'))
    assert "run.distance" in message and "at most 100 m" in message


@pytest.mark.parametrize("path", sorted((Path(__file__).resolve().parents[2] / "studies")
                                        .glob("*.toml")), ids=lambda path: path.stem)
def test_every_shipped_study_is_a_valid_spec(path: Path) -> None:
    """Each shipped study's keys, values and distributions pass the checks a run makes
    before anything runs (the sizing study's bore and valve keys included)."""
    parse_study(path.read_text(encoding="utf-8"))
