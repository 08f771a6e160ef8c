"""Compare a parameter file written by ``pneumaquad fit valve`` with thesis-rig.

The demo's stand-in lab data (docs/analysis.md, "The fitting example") is simulated with
thesis-rig, so its parameters are what the fit should give back. Prints the fitted
friction against thesis-rig's (and the peak of thesis-rig's Stribeck-tanh law, which a
stiction estimate from the force at motion onset approaches), the largest cutoff error,
the per-step equivalent areas from the file's header against thesis-rig's area
polynomials at the step voltages, and the fitted polynomials at those voltages against
thesis-rig's.

    .venv/bin/python docs/examples/compare_fit.py runs/fitted.toml
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np

from pneumaquad.core.physics.friction import stribeck_tanh_force
from pneumaquad.core.valve_fit import evaluate_equivalent_area
from pneumaquad.params import load_rig

STEP = re.compile(r"^# fit 'equivalent area at ([-+0-9.]+) V'")
AREA = re.compile(r"^#   port([12])_area \[m\^2\] = ([-+0-9.e]+)")


def header_areas(path: Path) -> dict[float, dict[int, float]]:
    """Per-step fitted areas {centered voltage: {port: area}} from the file's header."""
    areas: dict[float, dict[int, float]] = {}
    voltage = None
    for line in path.read_text().splitlines():
        if match := STEP.match(line):
            voltage = float(match.group(1))
            areas[voltage] = {}
        elif (match := AREA.match(line)) and voltage is not None:
            areas[voltage][int(match.group(1))] = float(match.group(2))
    return areas


def polynomial(valve, port: int, centered: float) -> float:
    side = getattr(valve, f"port{port}")
    return float(evaluate_equivalent_area(side.area_negative, side.area_positive, centered))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fitted", type=Path)
    fitted_path = parser.parse_args().fitted
    fitted, truth = load_rig(fitted_path), load_rig("thesis-rig")
    for key in ("static_force", "coulomb_force", "viscous_coefficient"):
        print(
            f"friction.{key}: {getattr(fitted.actuator.friction, key):.4g} "
            f"(thesis-rig {getattr(truth.actuator.friction, key):.4g})"
        )
    law = truth.actuator.friction
    peak = max(
        stribeck_tanh_force(
            v,
            law.static_force,
            law.coulomb_force,
            law.viscous_coefficient,
            law.stribeck_velocity,
            law.stribeck_exponent,
            law.tanh_coefficient,
        )
        for v in np.linspace(1e-6, 0.02, 20001)
    )
    print(
        f"thesis-rig's Stribeck-tanh law peaks at {peak:.2f} N = {peak / law.static_force:.3f} Fs"
    )
    cutoffs = []
    for port in (1, 2):
        for key in ("high_pressure_cutoff", "low_pressure_cutoff"):
            value = getattr(getattr(fitted.actuator.valve, f"port{port}"), key)
            cutoffs.append(value - getattr(getattr(truth.actuator.valve, f"port{port}"), key))
    print(f"cutoffs: largest difference {np.max(np.abs(cutoffs)):.2g} V")
    steps, curves = [], []
    print("centered [V]: step area / thesis-rig port 1, port 2; polynomial / thesis-rig")
    for voltage, areas in sorted(header_areas(fitted_path).items()):
        exact = [polynomial(truth.actuator.valve, port, voltage) for port in (1, 2)]
        step = [areas[port] / exact[port - 1] for port in (1, 2)]
        curve = [polynomial(fitted.actuator.valve, p, voltage) / exact[p - 1] for p in (1, 2)]
        steps += step
        curves += curve
        print(f"  {voltage:+.3f}: {step[0]:.4f} {step[1]:.4f}; {curve[0]:.4f} {curve[1]:.4f}")
    if steps:
        print(
            f"largest deviation: step areas {100 * np.max(np.abs(np.subtract(steps, 1))):.2f} %, "
            f"polynomials {100 * np.max(np.abs(np.subtract(curves, 1))):.2f} %"
        )


if __name__ == "__main__":
    main()
