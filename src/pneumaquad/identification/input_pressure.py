"""Input-pressure curves of the underlapped valve from fixed-piston tests (thesis 4.2.3).

With the piston held (the rig's spacer), each chamber settles at the input pressure its
valve port presents, so the settled pressures against the centered voltage trace the
tanh curves of eq 4.2.7-4.2.11 (Fig. 23). The library's model
(`pneumaquad.physics.valve.input_pressure`, array form `pneumaquad.valve_fit`) holds
supply and exhaust pressure and has two shape parameters per port: the high and low
pressure cutoffs C_HP and C_LP.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

from pneumaquad.params.schema import RigSetup
from pneumaquad.valve_fit import input_pressure

from .preprocess import IdentificationError
from .report import FitResult, covariance_from_jacobian, r_squared

__all__ = [
    "InputPressureCurves",
    "SteadyStatePoints",
    "chamber_port_numbers",
    "fit_input_pressure_curve",
    "input_pressure_curves",
    "steady_state_points",
]


def chamber_port_numbers(setup: RigSetup) -> tuple[int, int]:
    """(port feeding the cap chamber, port feeding the rod chamber), per ``valve.cap_port``."""
    cap = setup.actuator.valve.cap_port
    return cap, 3 - cap


def _centered(setup: RigSetup, command: ArrayLike) -> np.ndarray:
    valve = setup.actuator.valve
    saturated = np.clip(np.asarray(command, dtype=float), valve.min_voltage, valve.max_voltage)
    return saturated - valve.offset_voltage


@dataclass(frozen=True)
class SteadyStatePoints:
    """Settled chamber pressures of constant-command segments.

    Attributes
    ----------
    centered_voltage : numpy.ndarray
        [V].
    cap_pressure, rod_pressure : numpy.ndarray
        Mean absolute pressures over each segment's tail [Pa].
    cap_drift, rod_drift : numpy.ndarray
        Pressure change over the tail [Pa]; large values mean not yet settled.
    """

    centered_voltage: np.ndarray
    cap_pressure: np.ndarray
    rod_pressure: np.ndarray
    cap_drift: np.ndarray
    rod_drift: np.ndarray


def steady_state_points(
    recordings: Iterable[Mapping[str, np.ndarray]],
    setup: RigSetup,
    *,
    tail_fraction: float = 0.25,
    command_threshold: float = 0.05,
    min_samples: int = 20,
) -> SteadyStatePoints:
    """Steady-state pressures per held command, from fixed-piston recordings.

    Each recording may hold one voltage or a staircase; every constant-command segment
    of at least ``min_samples`` samples gives a point, the mean over its last
    ``tail_fraction``.

    Parameters
    ----------
    recordings : iterable of mapping
        Columns ``"command [V]"``, ``"cap pressure [Pa]"``, ``"rod pressure [Pa]"``,
        ``"time [s]"``.
    setup : RigSetup
        Valve offset and voltage range.
    tail_fraction : float
        Share of each segment averaged, in (0, 1].
    command_threshold : float
        Smallest command jump that starts a new segment [V].
    min_samples : int
        Shorter segments are skipped.

    Returns
    -------
    SteadyStatePoints

    Raises
    ------
    IdentificationError
        For missing columns or no usable segment.
    """
    if not 0.0 < tail_fraction <= 1.0:
        raise IdentificationError(f"tail_fraction must be in (0, 1], got {tail_fraction!r}")
    rows: list[tuple[float, float, float, float, float]] = []
    for recording in recordings:
        missing = [
            name
            for name in ("time [s]", "command [V]", "cap pressure [Pa]", "rod pressure [Pa]")
            if name not in recording
        ]
        if missing:
            raise IdentificationError(f"a spacer recording lacks the columns {missing}")
        command = np.asarray(recording["command [V]"], dtype=float)
        jumps = np.nonzero(np.abs(np.diff(command)) > command_threshold)[0] + 1
        bounds = [0, *jumps.tolist(), command.size]
        for first, last in itertools.pairwise(bounds):
            if last - first < min_samples:
                continue
            tail = slice(last - max(2, round(tail_fraction * (last - first))), last)
            pressures = [
                np.asarray(recording[name], dtype=float)[tail]
                for name in ("cap pressure [Pa]", "rod pressure [Pa]")
            ]
            halves = [np.array_split(values, 2) for values in pressures]
            rows.append(
                (
                    float(_centered(setup, np.median(command[first:last]))),
                    float(np.mean(pressures[0])),
                    float(np.mean(pressures[1])),
                    float(np.mean(halves[0][1]) - np.mean(halves[0][0])) * 2.0,
                    float(np.mean(halves[1][1]) - np.mean(halves[1][0])) * 2.0,
                )
            )
    if not rows:
        raise IdentificationError("no constant-command segment long enough in the recordings")
    columns = np.array(rows).T
    return SteadyStatePoints(*columns)


def fit_input_pressure_curve(
    centered_voltages: ArrayLike,
    pressures: ArrayLike,
    supply_pressure: float,
    exhaust_pressure: float,
) -> FitResult:
    """Least squares of the input-pressure curve, eq 4.2.7-4.2.11, for one port.

    Supply and exhaust pressure are held; the unknowns are the curve's centre and log
    width, so the cutoffs never coincide; the slope sign (supply at positive or negative
    voltage) is taken from the data. Standard errors of the cutoffs follow by the delta
    method.

    Parameters
    ----------
    centered_voltages : array_like
        [V].
    pressures : array_like
        Steady-state absolute pressures [Pa].
    supply_pressure, exhaust_pressure : float
        Absolute [Pa].

    Returns
    -------
    FitResult
        ``"high_pressure_cutoff [V]"``, ``"low_pressure_cutoff [V]"``.

    Raises
    ------
    IdentificationError
        With fewer than three points, or no convergence.
    """
    u = np.asarray(centered_voltages, dtype=float).ravel()
    p = np.asarray(pressures, dtype=float).ravel()
    if u.shape != p.shape or u.size < 3:
        raise IdentificationError("need at least three (voltage, pressure) pairs of equal length")
    span = supply_pressure - exhaust_pressure
    direction = float(np.sign(np.sum((u - u.mean()) * (p - p.mean())))) or 1.0
    middle = 0.5 * (supply_pressure + exhaust_pressure)
    start = [float(u[np.argmin(np.abs(p - middle))]), math.log(max(0.25 * np.ptp(u), 1e-3))]

    def cutoffs(unknowns: np.ndarray) -> tuple[float, float]:
        half_width = 0.5 * math.exp(unknowns[1])
        return unknowns[0] + direction * half_width, unknowns[0] - direction * half_width

    def residuals(unknowns: np.ndarray) -> np.ndarray:
        return input_pressure(u, supply_pressure, exhaust_pressure, *cutoffs(unknowns)) - p

    solution = least_squares(residuals, start, x_scale=[1.0, 1.0], f_scale=0.01 * span)
    if not solution.success:
        raise IdentificationError(f"input-pressure fit did not converge: {solution.message}")
    high, low = cutoffs(solution.x)
    half_width = 0.5 * math.exp(solution.x[1])
    gradient = np.array([[1.0, direction * half_width], [1.0, -direction * half_width]])
    covariance = gradient @ covariance_from_jacobian(solution.jac, solution.fun) @ gradient.T
    errors = np.sqrt(np.abs(np.diag(covariance)))
    keys = ("high_pressure_cutoff [V]", "low_pressure_cutoff [V]")
    return FitResult(
        name="input-pressure curve",
        parameters={keys[0]: float(high), keys[1]: float(low)},
        standard_errors={keys[0]: float(errors[0]), keys[1]: float(errors[1])},
        r_squared=r_squared(solution.fun, p),
        residual_rms=math.sqrt(float(solution.fun @ solution.fun) / p.size),
        n_points=int(p.size),
        residual_unit="Pa",
    )


@dataclass(frozen=True)
class InputPressureCurves:
    """Fitted input-pressure curves of both ports and the points behind them.

    Attributes
    ----------
    points : SteadyStatePoints
    fits : dict of int to FitResult
        Per valve port number (1, 2).
    """

    points: SteadyStatePoints
    fits: dict[int, FitResult]


def input_pressure_curves(
    recordings: Iterable[Mapping[str, np.ndarray]],
    setup: RigSetup,
    *,
    tail_fraction: float = 0.25,
    command_threshold: float = 0.05,
) -> InputPressureCurves:
    """Fit both ports' tanh input-pressure curves from fixed-piston recordings.

    The cap chamber's settled pressure is its port's input pressure (port
    ``valve.cap_port``), the rod chamber's that of the other port (thesis 4.2.3, Fig. 23).

    Parameters
    ----------
    recordings : iterable of mapping
        Fixed-piston (spacer) recordings at held commands, long enough to settle.
    setup : RigSetup
        Supply, exhaust, valve offset and range, port assignment.
    tail_fraction, command_threshold : float
        See `steady_state_points`.

    Returns
    -------
    InputPressureCurves
    """
    points = steady_state_points(
        recordings, setup, tail_fraction=tail_fraction, command_threshold=command_threshold
    )
    supply = setup.actuator.supply
    cap_port, rod_port = chamber_port_numbers(setup)
    fits = {
        port: fit_input_pressure_curve(
            points.centered_voltage, values, supply.supply_pressure, supply.exhaust_pressure
        )
        for port, values in ((cap_port, points.cap_pressure), (rod_port, points.rod_pressure))
    }
    return InputPressureCurves(points, dict(sorted(fits.items())))
