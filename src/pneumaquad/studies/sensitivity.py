"""Global sensitivity of a study's metrics to its varied parameters, through SALib.

A Latin hypercube or Sobol study samples every parameter over its whole distribution, so
any of its metrics can be analysed from the cases as they are, with no extra runs, by the
moment-independent method of Borgonovo (SALib ``delta``, its bias-corrected "balanced"
estimator): ``delta`` [-] measures how much knowing a parameter shifts the whole
distribution of the metric, ``S1`` [-] is the
first-order Sobol index (the share of the metric's variance that parameter explains
alone), each with the half-width of its 95 % bootstrap confidence interval. A Saltelli
design (``sampling = "saltelli"``) is made for Sobol's indices: :func:`sobol_indices`
gives the first-order index S1 and the total index ST (S1 plus every interaction the
parameter takes part in) with their intervals, from all its cases. A grid or a list is
not a random sample of the parameters, so it gets no table.
"""

from __future__ import annotations

import contextlib
import io
import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["MIN_CASES", "SensitivityRow", "SobolRow", "sensitivity_table", "sobol_indices"]

#: Fewest finite cases to estimate indices from.
MIN_CASES = 32
#: Bootstrap resamples of the confidence intervals.
RESAMPLES = 100


@dataclass(frozen=True)
class SensitivityRow:
    """Indices [-] of one parameter for one metric, with 95 % confidence half-widths."""

    metric: str
    parameter: str
    delta: float
    delta_confidence: float
    first_order: float
    first_order_confidence: float


def sensitivity_table(parameters: dict[str, np.ndarray], metrics: dict[str, np.ndarray],
                      seed: int = 0) -> list[SensitivityRow]:
    """Delta and first-order Sobol indices of every metric against every parameter.

    Parameters
    ----------
    parameters : dict of str to ndarray (n,)
        The varied numbers of the cases, by column name.
    metrics : dict of str to ndarray (n,)
        The metrics of the same cases; cases with a non-finite metric are left out of
        that metric's analysis.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    list of SensitivityRow
        Metric by metric, parameters in order; a metric with fewer than
        :data:`MIN_CASES` finite cases or no spread gives no rows.
    """
    from SALib.analyze import delta

    names = list(parameters)
    samples = np.column_stack([np.asarray(parameters[name], dtype=float) for name in names])
    bounds = [[float(np.min(column)), float(np.max(column))] for column in samples.T]
    rows = []
    for metric, values in metrics.items():
        values = np.asarray(values, dtype=float)
        finite = np.isfinite(values) & np.all(np.isfinite(samples), axis=1)
        if finite.sum() < MIN_CASES or np.ptp(values[finite]) == 0.0:
            continue
        problem = {"num_vars": len(names), "names": names, "bounds": bounds}
        quiet = io.StringIO()
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")  # SALib's notes on its binning
            found = delta.analyze(problem, samples[finite], values[finite],
                                  num_resamples=RESAMPLES, seed=seed % (2**32 - 1) + 1)
        for j, name in enumerate(names):
            rows.append(SensitivityRow(metric, name, float(found["delta_balanced"][j]),
                                       float(found["delta_balanced_conf"][j]),
                                       float(found["S1"][j]), float(found["S1_conf"][j])))
    return rows


@dataclass(frozen=True)
class SobolRow:
    """First-order and total Sobol indices [-] of one parameter for one metric, with
    95 % confidence half-widths."""

    metric: str
    parameter: str
    first_order: float
    first_order_confidence: float
    total: float
    total_confidence: float


def sobol_indices(names: list[str], metrics: dict[str, np.ndarray],
                  seed: int = 0) -> tuple[list[SobolRow], list[str]]:
    """Sobol indices of every metric of a complete Saltelli design.

    Parameters
    ----------
    names : list of str
        The varied parameters, in design order.
    metrics : dict of str to ndarray (N·(D+2),)
        Each metric over all cases, in case order.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    (rows, skipped)
        Rows metric by metric; the metrics left out because a case is missing or not
        finite (the estimator needs every case of the design) or they do not vary.
    """
    from SALib.analyze import sobol

    problem = {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names)}
    rows, skipped = [], []
    for metric, values in metrics.items():
        values = np.asarray(values, dtype=float)
        if (values.size % (len(names) + 2) or not np.all(np.isfinite(values))
                or np.ptp(values) == 0.0):
            skipped.append(metric)
            continue
        quiet = io.StringIO()
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = sobol.analyze(problem, values, calc_second_order=False,
                                  num_resamples=RESAMPLES, seed=seed % (2**32 - 1) + 1)
        for j, name in enumerate(names):
            rows.append(SobolRow(metric, name, float(found["S1"][j]),
                                 float(found["S1_conf"][j]), float(found["ST"][j]),
                                 float(found["ST_conf"][j])))
    return rows, skipped
