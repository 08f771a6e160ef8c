"""Valve identification for the underlapped valve model (thesis 4.2.3, App. B.2).

Three steps, as in the thesis:

1. Input-pressure curves from fixed-piston (spacer) tests: with the piston held, each
   chamber settles at its port's input pressure, so the steady-state pressures against
   the centered voltage give the tanh curves of eq 4.2.7-4.2.11. The library model
   (`pneumaquad.core.physics.valve.input_pressure`) has supply and exhaust pressure fixed and
   two shape parameters per port: the high and low pressure cutoffs C_HP, C_LP.
2. Equivalent orifice areas: for each open-loop step at a voltage u the thesis hand-tuned
   a discharge coefficient until simulated pressures and position matched. Here the areas
   at u are fitted by bounded least squares around the rig simulator.
3. Fourth-order polynomials through the areas, one per port and side of the offset
   (`pneumaquad.core.valve_fit`, App. B.2).

Voltages called *centered* are measured from the valve offset, after saturation. Steps 1
and 2 live in `pneumaquad.identification.input_pressure` and
`pneumaquad.identification.equivalent_area` and are re-exported here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pneumaquad.analysis.fits import FitResult, covariance_from_jacobian, r_squared
from pneumaquad.core.valve_fit import evaluate_equivalent_area, fit_equivalent_area_polynomials

from .equivalent_area import (
    AREA_MODES,
    START_TEMPERATURE_SOURCES,
    EquivalentAreaFit,
    equivalent_area_for_step,
    start_temperatures_from_hold,
)
from .input_pressure import (
    InputPressureCurves,
    SteadyStatePoints,
    chamber_port_numbers,
    fit_input_pressure_curve,
    input_pressure_curves,
    steady_state_points,
)
from .preprocess import IdentificationError

__all__ = [
    "AREA_MODES",
    "START_TEMPERATURE_SOURCES",
    "AreaPolynomials",
    "EquivalentAreaFit",
    "InputPressureCurves",
    "SteadyStatePoints",
    "area_polynomial_updates",
    "areas_table",
    "chamber_port_numbers",
    "equivalent_area_for_step",
    "fit_area_polynomials",
    "fit_input_pressure_curve",
    "input_pressure_curves",
    "start_temperatures_from_hold",
    "steady_state_points",
]


@dataclass(frozen=True)
class AreaPolynomials:
    """Equivalent-area polynomials of one port (App. B.2).

    Attributes
    ----------
    negative, positive : numpy.ndarray
        5 coefficients each, highest power first [m^2/V^n], for centered voltages
        <= 0 and > 0.
    fit : FitResult
        The same coefficients keyed ``"area_negative_c4 [m^2/V^4]"`` ...
        ``"area_positive_c0 [m^2]"`` with the standard errors of each side's least
        squares, R² and the RMS residual of the two-sided curve over all points [m^2].
    """

    negative: np.ndarray
    positive: np.ndarray
    fit: FitResult

    @property
    def residual_rms(self) -> float:
        """RMS of the fit residuals [m^2]."""
        return self.fit.residual_rms

    @property
    def n_points(self) -> int:
        """Points fitted."""
        return self.fit.n_points


def _coefficient_keys(side: str, order: int) -> list[str]:
    """``"area_<side>_c<k> [m^2/V^k]"``, highest power first (``np.polyval`` order)."""
    return [f"area_{side}_c{k} [m^2/V^{k}]" if k else f"area_{side}_c0 [m^2]"
            for k in range(order, -1, -1)]


def _side_errors(coefficients: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """One-sigma standard errors of one side's ordinary least-squares coefficients."""
    design = np.vander(x, coefficients.size)  # d(residual)/d(coefficient)
    residuals = np.polyval(coefficients, x) - y
    return np.sqrt(np.diag(covariance_from_jacobian(design, residuals)))


def fit_area_polynomials(
    voltages: ArrayLike, areas: Mapping[int, ArrayLike], order: int = 4
) -> dict[int, AreaPolynomials]:
    """Fourth-order polynomials per port and side of the offset (thesis 4.2.3.1, App. B.2).

    Uses `pneumaquad.core.valve_fit.fit_equivalent_area_polynomials`: ordinary least squares
    per side, the point at 0 V (if any) in both.

    Parameters
    ----------
    voltages : array_like
        Centered voltages [V] of the area points.
    areas : mapping of int to array_like
        Port number to its equivalent areas at ``voltages`` [m^2].
    order : int
        Polynomial order (4 in the thesis); each side needs more than ``order`` points.

    Returns
    -------
    dict of int to AreaPolynomials

    Raises
    ------
    IdentificationError
        With too few points on a side.
    """
    x = np.asarray(voltages, dtype=float).ravel()
    result = {}
    for port, values in areas.items():
        y = np.asarray(values, dtype=float).ravel()
        try:
            negative, positive = fit_equivalent_area_polynomials(x, y, order)
        except ValueError as error:
            raise IdentificationError(f"port {port}: {error}") from error
        fitted = evaluate_equivalent_area(negative, positive, x)
        keys = [*_coefficient_keys("negative", order), *_coefficient_keys("positive", order)]
        errors = np.concatenate([_side_errors(negative, x[x <= 0.0], y[x <= 0.0]),
                                 _side_errors(positive, x[x >= 0.0], y[x >= 0.0])])
        values_fitted = np.concatenate([negative, positive])
        result[port] = AreaPolynomials(
            negative=negative,
            positive=positive,
            fit=FitResult(
                name=f"area polynomials, port {port}",
                parameters=dict(zip(keys, map(float, values_fitted), strict=True)),
                standard_errors=dict(zip(keys, map(float, errors), strict=True)),
                r_squared=r_squared(fitted - y, y),
                residual_rms=float(np.sqrt(np.mean((fitted - y) ** 2))),
                n_points=int(y.size),
                residual_unit="m^2",
                details={"port": port, "order": order},
            ),
        )
    return result


def area_polynomial_updates(polynomials: Mapping[int, AreaPolynomials]) -> dict[str, list]:
    """Parameter-file updates ``{"valve.portN.area_negative": [...], ...}``."""
    updates: dict[str, list] = {}
    for port, fit in polynomials.items():
        updates[f"valve.port{port}.area_negative"] = [float(c) for c in fit.negative]
        updates[f"valve.port{port}.area_positive"] = [float(c) for c in fit.positive]
    return updates


def areas_table(fits: Sequence[EquivalentAreaFit]) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """Voltages and per-port areas of several step fits, for `fit_area_polynomials`."""
    voltages = np.array([fit.centered_voltage for fit in fits])
    return voltages, {port: np.array([fit.areas[port] for fit in fits]) for port in (1, 2)}
