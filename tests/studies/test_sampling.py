"""Designs: distributions read their units and quantiles, Latin hypercubes fill every
stratum, and cases and their seeds follow from the study seed alone."""

from __future__ import annotations

import numpy as np
import pytest
from study_files import FRICTION_STUDY

from pneumaquad.studies import case_seed, parse_study, study_cases
from pneumaquad.studies.distributions import parse_distribution
from pneumaquad.studies.sampling import unit_design


def test_quartiles_are_read_like_a_box_plot() -> None:
    quartiles = parse_distribution("q", {"distribution": "quartiles", "quartiles": [
        "3.5 lbf", "4.1 lbf", "4.4 lbf", "4.6 lbf", "5.0 lbf"]})
    assert quartiles.unit == "lbf"
    values = quartiles.from_unit_interval(np.array([0.25, 0.5, 0.75, 0.125]))
    assert values == pytest.approx([4.1, 4.4, 4.6, 3.8])


def test_a_truncated_normal_stays_within_its_bounds() -> None:
    normal = parse_distribution("n", {"distribution": "normal", "mean": "3 lbf",
                                      "std": "1 lbf", "low": "2.5 lbf", "high": "3.5 lbf"})
    values = normal.from_unit_interval(np.linspace(0.0, 1.0, 101))
    assert values.min() >= 2.5 and values.max() <= 3.5
    assert normal.from_unit_interval(np.array([0.5]))[0] == pytest.approx(3.0)


def test_a_log_normal_has_its_median_and_spread() -> None:
    spread = parse_distribution("l", {"distribution": "log-normal", "median": "2 mm",
                                      "geometric_std": 1.5})
    one_sigma = spread.from_unit_interval(np.array([0.5, 0.8413447460685429]))
    assert one_sigma == pytest.approx([2.0, 3.0])


def test_a_latin_hypercube_has_one_case_in_every_stratum() -> None:
    design = unit_design("latin-hypercube", 50, 3, seed=4)
    for column in design.T:
        assert sorted(np.floor(column * 50).astype(int)) == list(range(50))
    assert np.array_equal(design, unit_design("latin-hypercube", 50, 3, seed=4))
    assert not np.array_equal(design, unit_design("latin-hypercube", 50, 3, seed=5))


def test_cases_and_seeds_follow_from_the_study_seed() -> None:
    spec = parse_study(FRICTION_STUDY)
    cases = study_cases(spec)
    assert cases == study_cases(parse_study(FRICTION_STUDY))
    assert [case.seed for case in cases] == [case_seed(11, i) for i in range(8)]
    assert len({case.seed for case in cases}) == 8
    static = np.array([case.values[0] for case in cases])
    assert static.min() >= 3.5 and static.max() <= 5.0
    assert cases[0].overrides[0].startswith('friction.static_force="')
    assert cases[0].overrides[0].endswith(' lbf"')


def test_integers_and_choices_of_a_list_keep_their_kind() -> None:
    text = FRICTION_STUDY.split("[vary.")[0].replace(
        'sampling = "latin-hypercube"\ncases = 8', 'sampling = "list"') + """
[vary."simulation.substeps"]
values = [4, 5]

[vary."friction.model"]
values = ["stribeck_tanh", "lugre"]

[vary."run.voltage"]
values = ["6 V", "6.5 V"]
"""
    spec = parse_study(text)
    cases = study_cases(spec)
    assert cases[1].overrides == ("simulation.substeps=5", 'friction.model="lugre"')
    assert cases[1].run_options["voltage"] == "6.5 V"
    assert [p.column for p in spec.varied] == ["simulation.substeps", "friction.model",
                                               "run.voltage [V]"]
