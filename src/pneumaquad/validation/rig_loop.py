"""Closed-loop figures of the rig as thesis 4.3 reports them: the step time constant and
the sine lags.

Protocols (the thesis does not print its amplitudes; these are the demo's):

* Step train: the piston reference visits 0.4, 1.4, 0.6, 1.2 and 0.875 in for 2 s each
  (the demo's step train). The first level is approached from the rig's start at the end
  of the stroke and is left out, as the thesis left out its first step (l. 822); each of
  the other four steps is fitted with thesis eq (4.3.1) from the step instant over its
  2 s, and the time constants are averaged.
* Sines: 0.875 ± 0.4 in at 1, 3 and 5 rad/s for one settling cycle and four measured
  ones; the lag is the cross-correlation delay of the position behind the reference
  (:func:`pneumaquad.analysis.metrics.lag`) over the measured cycles.

Every protocol runs any number of rig setups at once (:func:`simulate_rigs`), which is
what the calibration of :mod:`pneumaquad.validation.calibration` needs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pneumaquad.analysis.fits import fit_first_order
from pneumaquad.analysis.metrics import lag
from pneumaquad.params.conversions import METRE_PER_INCH
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rigs
from pneumaquad.validation.published import RIG_SINE_RATES

__all__ = [
    "SINE_AMPLITUDE",
    "SINE_MEAN",
    "STEP_DWELL",
    "STEP_LEVELS",
    "RigLoopFigures",
    "rig_loop_figures",
    "rig_sine_lags",
    "rig_step_time_constants",
]

#: Step-train levels [m] and dwell [s].
STEP_LEVELS = tuple(level * METRE_PER_INCH for level in (0.4, 1.4, 0.6, 1.2, 0.875))
STEP_DWELL = 2.0
#: Sine mean and amplitude [m].
SINE_MEAN = 0.875 * METRE_PER_INCH
SINE_AMPLITUDE = 0.4 * METRE_PER_INCH
#: Cycles run before the lag is measured, and measured cycles.
SINE_SETTLING_CYCLES = 1
SINE_MEASURED_CYCLES = 4


@dataclass(frozen=True)
class RigLoopFigures:
    """Closed-loop figures of one rig setup.

    Attributes
    ----------
    time_constants : tuple of float
        First-order time constant of each fitted step [s].
    sine_rates : tuple of float
        Sine rates [rad/s].
    sine_lags : tuple of float
        Lag of the position behind the reference at each rate [s].
    """

    time_constants: tuple[float, ...]
    sine_rates: tuple[float, ...]
    sine_lags: tuple[float, ...]

    @property
    def time_constant(self) -> float:
        """Mean step time constant [s]."""
        return float(np.mean(self.time_constants))

    @property
    def time_constant_spread(self) -> float:
        """Standard deviation of the step time constants [s]."""
        return float(np.std(self.time_constants, ddof=1))


def rig_step_time_constants(setups: Sequence[RigSetup]) -> list[tuple[float, ...]]:
    """Run the step train on every setup; the fitted time constants [s] of each.

    Parameters
    ----------
    setups : sequence of RigSetup
        Rigs sharing the control step and substeps (fixed-step integrator).
    """
    control_step = setups[0].simulation.control_step
    reference = signals.step_train(STEP_LEVELS, STEP_DWELL, control_step)
    results = simulate_rigs(list(setups), np.tile(reference, (len(setups), 1)), True)
    constants = []
    for result in results:
        time = result.recording["time [s]"]
        position = result.recording["position [m]"]
        fitted = []
        for index in range(1, len(STEP_LEVELS)):
            start = index * STEP_DWELL
            window = (time >= start) & (time < start + STEP_DWELL)
            fit = fit_first_order(time[window], position[window], start_time=start)
            fitted.append(fit.parameters["time constant [s]"])
        constants.append(tuple(fitted))
    return constants


def rig_sine_lags(setups: Sequence[RigSetup],
                  rates: Sequence[float] = RIG_SINE_RATES) -> list[tuple[float, ...]]:
    """Run the sines at ``rates`` [rad/s] on every setup; the lag [s] at each rate."""
    control_step = setups[0].simulation.control_step
    lags: list[list[float]] = [[] for _ in setups]
    for rate in rates:
        period = 2.0 * math.pi / rate
        cycles = SINE_SETTLING_CYCLES + SINE_MEASURED_CYCLES
        reference = signals.sine(SINE_MEAN, SINE_AMPLITUDE, rate / (2.0 * math.pi),
                                 cycles * period, control_step)
        results = simulate_rigs(list(setups), np.tile(reference, (len(setups), 1)), True)
        for row, result in zip(lags, results, strict=True):
            time = result.recording["time [s]"]
            measured = time >= SINE_SETTLING_CYCLES * period
            row.append(lag(time[measured], result.recording["position [m]"][measured],
                           result.recording["reference position [m]"][measured],
                           max_lag=0.25 * period))
    return [tuple(row) for row in lags]


def rig_loop_figures(setups: Sequence[RigSetup]) -> list[RigLoopFigures]:
    """Step time constants and sine lags of every setup (:class:`RigLoopFigures`)."""
    constants = rig_step_time_constants(setups)
    lags = rig_sine_lags(setups)
    return [RigLoopFigures(constant, tuple(RIG_SINE_RATES), lag_row)
            for constant, lag_row in zip(constants, lags, strict=True)]
