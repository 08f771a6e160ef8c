"""What each optional component of the actuator model costs on its own: the profile that
explains the ordering of thesis Table 3 (5.5.3) on our kernels.

Each component and its simpler replacement run in a compiled loop over smooth inputs
(valve commands sweeping ±2 V about the offset, piston velocities ±0.05 m/s); the cost per
call times the calls per 1 ms control step estimates what the removal saves. The valve map
(areas and input pressures of both ports) is evaluated once per control step when the spool
has no lag; the friction law (force and slope) once per substep.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from pneumaquad.core.physics.valve import input_pressure, polynomial_area, simple_valve_area
from pneumaquad.core.pneumatics import friction_and_slope_of, friction_of, friction_slope_of
from pneumaquad.params import load_rig
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig.model import pack_rig_parameters

__all__ = ["ComponentCost", "component_costs"]

#: Calls per timed loop.
LOOP_CALLS = 50_000


@dataclass(frozen=True)
class ComponentCost:
    """One component against its replacement.

    Attributes
    ----------
    name : str
        ``component -> replacement``.
    ns_per_call, replacement_ns_per_call : float
        Median cost of one call [ns].
    calls_per_step : int
        Calls per 1 ms control step of the rig.
    transcendentals : str
        The transcendental functions one call evaluates.
    """

    name: str
    ns_per_call: float
    replacement_ns_per_call: float
    calls_per_step: int
    transcendentals: str

    @property
    def saving_us(self) -> float:
        """Estimated saving per control step [µs]."""
        return (self.ns_per_call - self.replacement_ns_per_call) * self.calls_per_step / 1e3


@njit(cache=False)
def _polynomial_loop(centered, negative, positive):
    total = 0.0
    for u in centered:
        total += polynomial_area(u, negative, positive)
    return total


@njit(cache=False)
def _linear_loop(centered, max_area, leak_area, full_scale):
    total = 0.0
    for u in centered:
        total += 0.09 * simple_valve_area(u, max_area, leak_area, full_scale)
    return total


@njit(cache=False)
def _tanh_pressure_loop(centered, supply, exhaust, high, low):
    total = 0.0
    for u in centered:
        total += input_pressure(u, supply, exhaust, high, low)
    return total


@njit(cache=False)
def _plain_pressure_loop(centered, supply, exhaust):
    total = 0.0
    for u in centered:
        total += supply if u >= 0.0 else exhaust
    return total


@njit(cache=False)
def _friction_loop(p, velocities):
    """Force and slope together, as the rig's mechanics substep evaluates them."""
    total = 0.0
    for v in velocities:
        force, slope = friction_and_slope_of(p, v, 0.0)
        total += force + slope
    return total


@njit(cache=False)
def _friction_apart_loop(p, velocities):
    """Force and slope asked for apart (``friction_of`` and ``friction_slope_of``): the
    Stribeck curve and the tanh evaluated twice."""
    total = 0.0
    for v in velocities:
        total += friction_of(p, v, 0.0) + friction_slope_of(p, v, 0.0)
    return total


def _median_ns(call, repeats: int) -> float:
    call()  # compiles
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        samples.append((time.perf_counter() - start) / LOOP_CALLS * 1e9)
    return float(np.median(samples))


def component_costs(setup: RigSetup | None = None, repeats: int = 15) -> list[ComponentCost]:
    """Time each optional component of ``setup`` (default thesis-rig) and its replacement.

    Parameters
    ----------
    setup : RigSetup, optional
        The rig whose parameters the components use.
    repeats : int
        Timed loops per component; the median counts.
    """
    setup = load_rig("thesis-rig") if setup is None else setup
    wave = np.sin(np.linspace(0.0, 60.0 * np.pi, LOOP_CALLS))
    centered, velocities = 2.0 * wave, 0.05 * wave
    row = pack_rig_parameters(setup)[0]
    viscous = pack_rig_parameters(load_rig("thesis-rig", ['friction.model="viscous"']))[0]
    negative = row["cap_polynomial_negative"].copy()
    positive = row["cap_polynomial_positive"].copy()
    supply, exhaust = row["supply_pressure"], row["exhaust_pressure"]
    high, low = row["cap_high_pressure_cutoff"], row["cap_low_pressure_cutoff"]

    def ns(call) -> float:
        return _median_ns(call, repeats)

    substeps = setup.simulation.substeps
    return [
        ComponentCost("area polynomials -> linear area",
                      ns(lambda: _polynomial_loop(centered, negative, positive)),
                      ns(lambda: _linear_loop(centered, 1e-5, 2e-7, 5.0)), 2,
                      "none (a 4th-order polynomial, Horner)"),
        ComponentCost("tanh input pressures -> plain",
                      ns(lambda: _tanh_pressure_loop(centered, supply, exhaust, high, low)),
                      ns(lambda: _plain_pressure_loop(centered, supply, exhaust)), 2,
                      "tanh"),
        ComponentCost("Stribeck-tanh (force + slope) -> viscous",
                      ns(lambda: _friction_loop(row, velocities)),
                      ns(lambda: _friction_loop(viscous, velocities)), substeps,
                      "exp, pow, tanh"),
        ComponentCost("Stribeck-tanh force and slope apart -> together",
                      ns(lambda: _friction_apart_loop(row, velocities)),
                      ns(lambda: _friction_loop(row, velocities)), substeps,
                      "2 exp, 2 pow, 2 tanh -> exp, pow, tanh"),
    ]
