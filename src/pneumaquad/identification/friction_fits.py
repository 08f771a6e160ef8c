"""Least-squares fits of friction laws to (velocity, friction) samples (thesis 4.2.2).

The Coulomb-viscous law (eq 4.2.4, sliding branch) is linear in its parameters and is
solved directly; the Stribeck-tanh law (eq 4.2.6) is fitted with bounded
`scipy.optimize.least_squares` using the library's own force law
(`pneumaquad.core.physics.friction.stribeck_tanh_force`). Both report standard errors from the
Jacobian, R² and the residual RMS in a `FitResult`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from pneumaquad.analysis.fits import FitResult, covariance_from_jacobian, r_squared
from pneumaquad.core.jit import compiled
from pneumaquad.core.physics.friction import stribeck_tanh_force

from .preprocess import IdentificationError

__all__ = [
    "STRIBECK_TANH_PARAMETERS",
    "fit_coulomb_viscous",
    "fit_stribeck_tanh",
    "stribeck_tanh_curve",
]

#: Parameters of the Stribeck-tanh law (eq 4.2.6): parameter-file name and SI unit.
STRIBECK_TANH_PARAMETERS = {
    "static_force": "N",
    "coulomb_force": "N",
    "viscous_coefficient": "N*s/m",
    "stribeck_velocity": "m/s",
    "stribeck_exponent": "-",
    "tanh_coefficient": "s/m",
}


def _checked(velocity: ArrayLike, friction: ArrayLike, minimum: int) -> tuple[np.ndarray, ...]:
    v = np.asarray(velocity, dtype=float).ravel()
    f = np.asarray(friction, dtype=float).ravel()
    if v.shape != f.shape:
        raise IdentificationError(f"{v.size} velocities but {f.size} friction values")
    finite = np.isfinite(v) & np.isfinite(f)
    v, f = v[finite], f[finite]
    if v.size < minimum:
        raise IdentificationError(f"need at least {minimum} finite friction samples, got {v.size}")
    return v, f


def fit_coulomb_viscous(velocity: ArrayLike, friction: ArrayLike) -> FitResult:
    """Linear least squares of F = F_C·sign(v) + C_V·v (eq 4.2.4, sliding branch).

    Parameters
    ----------
    velocity : array_like
        Sliding velocities [m/s] (both directions may be mixed).
    friction : array_like
        Friction at those velocities [N], opposing positive velocity when positive.

    Returns
    -------
    FitResult
        ``"coulomb_force [N]"``, ``"viscous_coefficient [N*s/m]"``.

    Raises
    ------
    IdentificationError
        With fewer than three samples or velocities that do not separate F_C from C_V.
    """
    v, f = _checked(velocity, friction, 3)
    design = np.column_stack([np.sign(v), v])
    if np.linalg.matrix_rank(design) < 2:
        raise IdentificationError("the velocities do not separate Coulomb from viscous friction")
    solution, *_ = np.linalg.lstsq(design, f, rcond=None)
    residuals = f - design @ solution
    covariance = covariance_from_jacobian(design, residuals)
    keys = ("coulomb_force [N]", "viscous_coefficient [N*s/m]")
    return FitResult(
        name="coulomb-viscous friction",
        parameters=dict(zip(keys, map(float, solution), strict=True)),
        standard_errors=dict(zip(keys, map(float, np.sqrt(np.diag(covariance))), strict=True)),
        r_squared=r_squared(residuals, f),
        residual_rms=math.sqrt(float(residuals @ residuals) / f.size),
        n_points=int(f.size),
        residual_unit="N",
        details={"velocity range [m/s]": (float(v.min()), float(v.max()))},
    )


@compiled
def _stribeck_tanh_array(velocity, fs, fc, cv, vs, exponent, ktanh):
    out = np.empty(velocity.shape[0])
    for index in range(velocity.shape[0]):
        out[index] = stribeck_tanh_force(velocity[index], fs, fc, cv, vs, exponent, ktanh)
    return out


def stribeck_tanh_curve(velocity: ArrayLike, parameters: Mapping[str, float]) -> np.ndarray:
    """Stribeck-tanh friction (eq 4.2.6, `pneumaquad.core.physics.friction`) at many velocities.

    Parameters
    ----------
    velocity : array_like
        [m/s].
    parameters : mapping
        Values by the names of `STRIBECK_TANH_PARAMETERS` (SI).

    Returns
    -------
    numpy.ndarray
        Friction [N].
    """
    v = np.ascontiguousarray(np.asarray(velocity, dtype=float).ravel())
    return _stribeck_tanh_array(v, *(float(parameters[name]) for name in STRIBECK_TANH_PARAMETERS))


#: Fitted unknowns: F_S, F_C, C_V, log v_S, i, log k_tanh (order of the parameters).
_LOWER = np.array([0.0, 0.0, 0.0, math.log(1e-5), 0.5, math.log(10.0)])
_UPPER = np.array([1e4, 1e4, 1e4, math.log(1.0), 20.0, math.log(1e6)])
_LOGARITHMIC = np.array([False, False, False, True, False, True])


def _to_unknowns(values: Mapping[str, float]) -> np.ndarray:
    unknowns = np.array([float(values[name]) for name in STRIBECK_TANH_PARAMETERS])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(_LOGARITHMIC, np.log(np.where(_LOGARITHMIC, unknowns, 1.0)), unknowns)


def _to_values(unknowns: np.ndarray) -> dict[str, float]:
    values = np.where(_LOGARITHMIC, np.exp(np.where(_LOGARITHMIC, unknowns, 0.0)), unknowns)
    return dict(zip(STRIBECK_TANH_PARAMETERS, map(float, values), strict=True))


def fit_stribeck_tanh(
    velocity: ArrayLike,
    friction: ArrayLike,
    initial: Mapping[str, float],
    fixed: Iterable[str] = (),
) -> FitResult:
    """Bounded least squares of the Stribeck-tanh law, eq 4.2.6.

    F = [F_C + (F_S - F_C)·exp(-(|v|/v_S)^i)]·tanh(k_tanh·v) + C_V·v with bounds F_S, F_C,
    C_V in [0, 1e4], v_S in [1e-5, 1] m/s, i in [0.5, 20], k_tanh in [10, 1e6] s/m (v_S
    and k_tanh fitted as logarithms). Standard errors come from the Jacobian at the
    solution (delta method for v_S and k_tanh).

    Parameters
    ----------
    velocity : array_like
        [m/s]; the Stribeck parameters need samples at speeds of the order of v_S.
    friction : array_like
        [N], opposing positive velocity when positive.
    initial : mapping
        Initial values by the names of `STRIBECK_TANH_PARAMETERS` (SI), e.g.
        ``setup.actuator.friction.model_dump()`` updated with the stiction and
        Coulomb-viscous estimates; other keys are ignored.
    fixed : iterable of str
        Names held at their initial value (poorly excited ones, often
        ``stribeck_exponent`` and ``tanh_coefficient``); their standard error is 0.

    Returns
    -------
    FitResult
        The six parameters as ``"name [unit]"``.

    Raises
    ------
    IdentificationError
        For too few samples, unknown names, or an initial value outside the bounds.
    """
    v, f = _checked(velocity, friction, 7)
    names = list(STRIBECK_TANH_PARAMETERS)
    fixed = set(fixed)
    missing = sorted(set(names) - set(initial))
    if missing or fixed - set(names):
        raise IdentificationError(
            f"initial values need {names} (missing {missing}); fixed names must be among "
            f"them (unknown {sorted(fixed - set(names))})"
        )
    start = _to_unknowns(initial)
    if not np.all((start >= _LOWER) & (start <= _UPPER)):
        raise IdentificationError(f"initial values {dict(initial)} are outside the fit bounds")
    free = np.array([name not in fixed for name in names])
    if not free.any():
        raise IdentificationError("every parameter is fixed: nothing to fit")

    def full(free_values: np.ndarray) -> np.ndarray:
        values = start.copy()
        values[free] = free_values
        return values

    def residuals(free_values: np.ndarray) -> np.ndarray:
        return stribeck_tanh_curve(v, _to_values(full(free_values))) - f

    from scipy.optimize import least_squares  # SciPy loads on first use: it is slow to import
    solution = least_squares(
        residuals,
        np.clip(start[free], _LOWER[free] + 1e-12, _UPPER[free] - 1e-12),
        bounds=(_LOWER[free], _UPPER[free]),
        x_scale="jac",
        max_nfev=200 * int(free.sum()),
    )
    unknowns = full(solution.x)
    values = _to_values(unknowns)
    covariance = np.zeros((len(names), len(names)))
    covariance[np.ix_(free, free)] = covariance_from_jacobian(solution.jac, solution.fun)
    # v_S and k_tanh are fitted as logarithms: d(value) = value·d(log value).
    scale = np.where(_LOGARITHMIC, [values[name] for name in names], 1.0)
    with np.errstate(invalid="ignore"):
        deviations = np.sqrt(np.abs(np.diag(covariance))) * scale
    errors = dict(zip(names, map(float, deviations), strict=True))
    keys = {name: f"{name} [{unit}]" for name, unit in STRIBECK_TANH_PARAMETERS.items()}
    return FitResult(
        name="stribeck-tanh friction",
        parameters={keys[name]: values[name] for name in names},
        standard_errors={keys[name]: float(errors[name]) for name in names},
        r_squared=r_squared(solution.fun, f),
        residual_rms=math.sqrt(float(solution.fun @ solution.fun) / f.size),
        n_points=int(f.size),
        residual_unit="N",
        details={"fixed": sorted(fixed), "converged": bool(solution.success)},
    )
