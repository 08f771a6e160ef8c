"""The thesis controller set: PID gains calibrated so that the closed loop reproduces the
figures thesis 4.3 and 5.5.2 publish (:mod:`pneumaquad.validation.published`).

The thesis prints no gains. Its published closed-loop figures are few (a step time
constant and sine lags on the rig; one sine lag per leg joint and beta's being "a slower
version" of gamma), so the calibration keeps the shape of our own tuning and fits the
fewest factors that the figures determine:

* rig: gains = tuned gains × ``scale``, the integral gain × ``integral factor`` too; two
  factors for two figures (step time constant 0.082 s, lag at 1 rad/s 0.08 s);
* gamma (the rig's cylinder): the rig's gains × ``scale``; one factor for the sine lag
  (0.16 s);
* alpha: the rig's gains × ``scale``, in the middle (geometrically) of the band of scales
  where the walking motion of 5.5.2.4 limit-cycles with alpha's full gain and not with
  75 % of it, as the thesis's alpha did (5.5.2.3-5.5.2.4); the band's lower edge is the
  onset of the limit cycle (bisection), its upper edge that onset / 0.75;
* beta: the rig's gains × ``scale``, the integral gain × ``integral factor`` too; two
  factors for the sine lag (0.16 s) and a mean step rise time 1.25 × gamma's.

The factors are found by least squares on their logarithms (scipy's ``least_squares``);
each evaluation is a closed-loop simulation of the protocols of
:mod:`pneumaquad.validation.rig_loop` and :mod:`pneumaquad.validation.leg_loop`. The
resulting gains are what ``thesis-rig-thesis-pid.toml`` and
``crr-quadruped-thesis-pid.toml`` ship; ``docs/examples/thesis_calibration.py`` re-runs
this.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from pneumaquad.analysis.fits import parameter_name_and_unit
from pneumaquad.identification.controller_data import GAIN_KEYS
from pneumaquad.params import load_rig
from pneumaquad.params.schema import RigSetup
from pneumaquad.validation.leg_loop import JointFigures, foot_cycle_figures, joint_figures
from pneumaquad.validation.published import (
    BETA_RISE_TO_GAMMA,
    BETA_SINE_LAG,
    GAMMA_SINE_LAG,
    RIG_SINE_LAG_BOUNDS,
    RIG_TIME_CONSTANT,
)
from pneumaquad.validation.rig_loop import rig_loop_figures

__all__ = [
    "ALPHA_SCALE_BRACKET",
    "BETA_INTEGRAL_FACTORS",
    "GAIN_FIELDS",
    "LIMIT_CYCLE_OSCILLATION",
    "THESIS_ALPHA_GAIN_SCALE",
    "CalibratedGains",
    "alpha_limit_cycles",
    "calibrate_alpha",
    "calibrate_beta",
    "calibrate_gamma",
    "calibrate_rig",
    "calibrate_thesis_controllers",
    "gain_overrides",
]

#: The PID gains the calibration scales, as (key, unit) of the parameter files: the
#: controller fit's gains (:data:`pneumaquad.identification.controller_data.GAIN_KEYS`).
GAIN_FIELDS = tuple(parameter_name_and_unit(key) for key in GAIN_KEYS)
#: Integral factors tried for beta (:func:`calibrate_beta`) [-].
BETA_INTEGRAL_FACTORS = (0.1, 0.15, 0.22, 0.33, 0.5)
#: The thesis's reduced alpha gain (5.5.2.4, l. 1135) [-].
THESIS_ALPHA_GAIN_SCALE = 0.75
#: Alpha error RMS above 3 Hz in the walking motion that counts as a limit cycle [rad]
#: (without one it stays near 1.5 deg, with one near 10 deg).
LIMIT_CYCLE_OSCILLATION = np.radians(5.0)
#: Bracket of the alpha scale searched for the limit cycle's onset [-], and the bisections.
ALPHA_SCALE_BRACKET = (1.0, 6.0)
ALPHA_BISECTIONS = 7
#: Relative step of the finite differences on the log-factors [-].
_DIFFERENCE_STEP = 0.03


@dataclass(frozen=True)
class CalibratedGains:
    """Gains found for one controller.

    Attributes
    ----------
    controller : str
        ``rig``, ``alpha``, ``beta`` or ``gamma``.
    gains : tuple of float
        Kp [V/m], Ki [V/(m s)], Kd [V s/m].
    factors : dict of str to float
        The fitted factors on the tuned gains [-].
    residuals : tuple of float
        Relative misses of the targets at the solution [-].
    """

    controller: str
    gains: tuple[float, float, float]
    factors: dict[str, float]
    residuals: tuple[float, ...]


def gain_overrides(section: str, gains: Sequence[float]) -> list[str]:
    """``--set`` overrides of the three PID gains of ``section`` (e.g. ``controller`` or
    ``controller.beta``), SI values with units."""
    return [f'{section}.{key}="{float(value)!r} {unit}"'
            for (key, unit), value in zip(GAIN_FIELDS, gains, strict=True)]


def _tuned(table) -> np.ndarray:
    return np.array([getattr(table, key) for key, _ in GAIN_FIELDS])


def _solve(residuals: Callable[[np.ndarray], np.ndarray], start: Sequence[float],
           jacobian: Callable[[np.ndarray], np.ndarray] | str = "2-point") -> np.ndarray:
    solution = least_squares(residuals, np.log(np.asarray(start, dtype=float)),
                             jac=jacobian, diff_step=_DIFFERENCE_STEP, x_scale=1.0,
                             xtol=1e-3, ftol=1e-4, max_nfev=40)
    return np.exp(solution.x)


def _rig_gains(tuned: np.ndarray, factors: np.ndarray) -> np.ndarray:
    scale, integral = factors
    return tuned * scale * np.array([1.0, integral, 1.0])


def calibrate_rig(params: str = "thesis-rig",
                  start: Sequence[float] = (0.45, 3.0)) -> CalibratedGains:
    """Rig gains with the thesis's step time constant and 1 rad/s sine lag (4.3).

    Parameters
    ----------
    params : str
        The rig parameter set whose tuned ``[controller]`` gives the shape.
    start : sequence of two floats
        Starting ``scale`` and ``integral factor`` [-].
    """
    base = load_rig(params)
    tuned = _tuned(base.controller)
    targets = np.array([RIG_TIME_CONSTANT, RIG_SINE_LAG_BOUNDS[0]])

    def setups(factor_sets: Sequence[np.ndarray]) -> list[RigSetup]:
        return [load_rig(params, gain_overrides("controller", _rig_gains(tuned, f)))
                for f in factor_sets]

    def misses(log_factor_sets: Sequence[np.ndarray]) -> np.ndarray:
        figures = rig_loop_figures(setups([np.exp(x) for x in log_factor_sets]))
        values = np.array([[f.time_constant, f.sine_lags[0]] for f in figures])
        return values / targets - 1.0

    def residuals(x: np.ndarray) -> np.ndarray:
        return misses([x])[0]

    def jacobian(x: np.ndarray) -> np.ndarray:
        # the centre and both perturbations in one compiled run of three rigs
        shifted = [x] + [x + _DIFFERENCE_STEP * np.eye(2)[i] for i in range(2)]
        values = misses(shifted)
        return ((values[1:] - values[0]) / _DIFFERENCE_STEP).T

    factors = _solve(residuals, start, jacobian)
    return CalibratedGains("rig", tuple(_rig_gains(tuned, factors)),
                           {"scale": float(factors[0]), "integral factor": float(factors[1])},
                           tuple(residuals(np.log(factors))))


def _joint(joint: str, gains: np.ndarray, params: str) -> JointFigures:
    return joint_figures(joint, params, gain_overrides(f"controller.{joint}", gains))


def calibrate_gamma(rig_gains: Sequence[float], params: str = "crr-quadruped",
                    start: float = 0.9) -> tuple[CalibratedGains, JointFigures]:
    """Gamma gains with the thesis's sine lag (5.5.2.1): the rig's calibrated gains
    ``rig_gains`` (Kp, Ki, Kd; gamma's cylinder is the rig's) times one ``scale``; the
    gains and gamma's figures with them."""
    shape = np.asarray(rig_gains, dtype=float)

    def residuals(x: np.ndarray) -> np.ndarray:
        return np.array([_joint("gamma", shape * np.exp(x[0]), params).sine_lag
                         / GAMMA_SINE_LAG - 1.0])

    (scale,) = _solve(residuals, [start])
    gains = shape * scale
    return (CalibratedGains("gamma", tuple(gains), {"scale": float(scale)},
                            tuple(residuals(np.log([scale])))),
            _joint("gamma", gains, params))


def calibrate_beta(rig_gains: Sequence[float], gamma_rise_time: float,
                   params: str = "crr-quadruped",
                   integral_factors: Sequence[float] = BETA_INTEGRAL_FACTORS,
                   start: float = 0.85) -> tuple[CalibratedGains, JointFigures]:
    """Beta gains with the thesis's fast-sine lag (5.5.2.2) and a mean step rise time
    :data:`BETA_RISE_TO_GAMMA` times ``gamma_rise_time`` [s].

    The gains are the rig's times a ``scale``, the integral gain times an ``integral
    factor`` too. The step rise time is not smooth enough in the factors for a joint
    least-squares fit (a step that sticks changes it by a jump), so for each of
    ``integral_factors`` the scale is solved for the lag, and the factor whose rise time
    comes closest to the target is kept.
    """
    shape = np.asarray(rig_gains, dtype=float)
    target_rise = BETA_RISE_TO_GAMMA * gamma_rise_time
    best: tuple[float, CalibratedGains, JointFigures] | None = None
    for integral in integral_factors:
        weights = shape * np.array([1.0, integral, 1.0])

        def residuals(x: np.ndarray, weights: np.ndarray = weights) -> np.ndarray:
            return np.array([_joint("beta", weights * np.exp(x[0]), params).sine_lag
                             / BETA_SINE_LAG - 1.0])

        (scale,) = _solve(residuals, [start])
        figures = _joint("beta", weights * scale, params)
        miss = abs(figures.rise_time / target_rise - 1.0)
        if best is None or miss < best[0]:
            found = CalibratedGains(
                "beta", tuple(weights * scale),
                {"scale": float(scale), "integral factor": float(integral)},
                (figures.sine_lag / BETA_SINE_LAG - 1.0, figures.rise_time / target_rise - 1.0))
            best = (miss, found, figures)
    assert best is not None
    return best[1], best[2]


def alpha_limit_cycles(gains: Sequence[float], params: str = "crr-quadruped") -> bool:
    """Whether alpha limit-cycles in the walking motion (5.5.2.4) with ``gains`` (Kp, Ki,
    Kd) at full gain: its tracking error above 3 Hz exceeds
    :data:`LIMIT_CYCLE_OSCILLATION`."""
    figures = foot_cycle_figures(1.0, params, gain_overrides("controller.alpha", gains))
    return bool(np.radians(figures[0].oscillation) > LIMIT_CYCLE_OSCILLATION)


def calibrate_alpha(rig_gains: Sequence[float],
                    params: str = "crr-quadruped") -> CalibratedGains:
    """Alpha gains that limit-cycle in the walking motion at full gain and not at
    :data:`THESIS_ALPHA_GAIN_SCALE` (module docstring).

    Raises
    ------
    ValueError
        When alpha does not limit-cycle at the bracket's top or already does at its bottom.
    """
    shape = np.asarray(rig_gains, dtype=float)
    low, high = ALPHA_SCALE_BRACKET
    if alpha_limit_cycles(shape * low, params) or not alpha_limit_cycles(shape * high, params):
        raise ValueError(f"the alpha limit cycle's onset is not within scales {low}-{high}")
    for _ in range(ALPHA_BISECTIONS):
        middle = float(np.sqrt(low * high))
        if alpha_limit_cycles(shape * middle, params):
            high = middle
        else:
            low = middle
    onset = float(np.sqrt(low * high))
    scale = onset / np.sqrt(THESIS_ALPHA_GAIN_SCALE)
    return CalibratedGains("alpha", tuple(shape * scale),
                           {"scale": scale, "limit-cycle onset scale": onset}, ())


def calibrate_thesis_controllers(rig_params: str = "thesis-rig",
                                 robot_params: str = "crr-quadruped") -> list[CalibratedGains]:
    """The whole thesis controller set, in the order the figures need it: rig, gamma (on
    the rig's gains), beta (on gamma's rise time), alpha."""
    rig = calibrate_rig(rig_params)
    gamma, gamma_figures = calibrate_gamma(rig.gains, robot_params)
    beta, _ = calibrate_beta(rig.gains, gamma_figures.rise_time, robot_params)
    alpha = calibrate_alpha(rig.gains, robot_params)
    return [rig, gamma, beta, alpha]
