"""From a study spec to its cases: the design, each case's values, overrides and seed.

The whole design is drawn once from the study seed, before any case runs, so the cases do
not depend on which executor runs them, in what order, or whether the study was resumed.
Each case also gets its own seed (:func:`case_seed`) from the study seed and its index,
for anything random within the run (the rough terrain of a robot run with
``seed = "case"``).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .spec import StudySpec

__all__ = ["Case", "case_seed", "study_cases", "unit_design"]


@dataclass(frozen=True)
class Case:
    """One case of a study.

    Parameters
    ----------
    index : int
        Its place in the design, from 0.
    seed : int
        Its own seed (:func:`case_seed`).
    values : tuple
        The varied values, in the order of ``spec.varied``: numbers in each key's unit,
        or texts/booleans.
    overrides : tuple of str
        The ``--set`` items of the varied parameter keys.
    run_options : dict
        The run options as a spec writes them, varied ``run.*`` options applied.
    """

    index: int
    seed: int
    values: tuple[Any, ...]
    overrides: tuple[str, ...]
    run_options: dict[str, Any] = field(default_factory=dict)


def case_seed(study_seed: int, index: int) -> int:
    """The seed of case ``index`` of a study seeded ``study_seed``: a 31-bit integer from
    NumPy's SeedSequence of (study seed, index), so neighbouring cases get unrelated
    streams."""
    state = np.random.SeedSequence([study_seed, index]).generate_state(1, np.uint32)[0]
    return int(state) >> 1


def unit_design(sampling: str, cases: int, dimensions: int, seed: int) -> np.ndarray:
    """A (cases, dimensions) design on the unit cube (0, 1)^d.

    Latin hypercube: one sample in each of ``cases`` equal strata of every dimension, the
    strata paired at random (not optimised against correlation: that takes about half a
    second for a few hundred cases, a share of a rig study's time); Sobol: the first
    ``cases`` points of a scrambled Sobol sequence. Both are drawn from ``seed``.
    """
    from scipy.stats import qmc  # here: a study's worker processes never draw designs

    rng = np.random.default_rng(seed)
    if sampling == "latin-hypercube":
        return qmc.LatinHypercube(dimensions, rng=rng).random(cases)
    if sampling == "sobol":
        return qmc.Sobol(dimensions, scramble=True, rng=rng).random(cases)
    if sampling == "saltelli":
        from SALib.sample import sobol as saltelli

        problem = {"num_vars": dimensions, "names": [f"x{j}" for j in range(dimensions)],
                   "bounds": [[0.0, 1.0]] * dimensions}
        base = cases // (dimensions + 2)
        return saltelli.sample(problem, base, calc_second_order=False, seed=seed)
    raise ValueError(f"{sampling!r} is not a sampled design")


def _value_rows(spec: StudySpec) -> list[tuple[Any, ...]]:
    """Each case's varied values, in case order."""
    if spec.sampling == "grid":
        return list(itertools.product(*(p.values for p in spec.varied)))
    if spec.sampling == "list":
        return list(zip(*(p.values for p in spec.varied), strict=True))
    design = unit_design(spec.sampling, spec.cases, len(spec.varied), spec.seed)
    columns = [p.distribution.from_unit_interval(design[:, j])
               for j, p in enumerate(spec.varied)]
    return [tuple(float(column[i]) for column in columns) for i in range(spec.cases)]


def study_cases(spec: StudySpec) -> list[Case]:
    """Every case of the study, in index order (module docstring)."""
    cases = []
    for index, values in enumerate(_value_rows(spec)):
        overrides = []
        options = dict(spec.run.options)
        for parameter, value in zip(spec.varied, values, strict=True):
            if parameter.key.startswith("run."):
                options[parameter.key[4:]] = parameter.spec_value(value)
            else:
                overrides.append(parameter.override(value))
        cases.append(Case(index, case_seed(spec.seed, index), tuple(values), tuple(overrides),
                          options))
    return cases
