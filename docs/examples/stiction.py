"""Measure the stiction figures of the README ("The model") and docs/physics.md (Friction).

The demo's slow closed-loop sine (`make demo`, section "Stiction at slow speed"): thesis-rig,
0.3 in about 0.875 in (mid-stroke) at 0.1 Hz for 20 s, the shipped PID, once with
Stribeck-tanh and once with LuGre friction. Over the run after its first 2 s (as the demo
counts) it prints, per friction model:

* the fraction of time the piston moves slower than 10 µm/s (the demo's "at rest"), and
  the median speed of those samples;
* the speed the piston creeps at between slips: the median and the quartiles of |v| over
  the samples slower than 1 mm/s (the slips, up to ~10 mm/s, are faster);
* the tracking RMSE.

    .venv/bin/python docs/examples/stiction.py
"""

from __future__ import annotations

import numpy as np

from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

INCH = 0.0254
AT_REST = 1e-5  # [m/s], the demo's threshold
SLIP = 1e-3  # [m/s]: slower than this is creep, not a slip
SKIP = 2.0  # [s] of start-up left out, as in the demo


def measure(model: str) -> dict[str, float]:
    """The figures of one friction model."""
    setup = load_rig("thesis-rig", [f'friction.model="{model}"'])
    reference = signals.sine(0.875 * INCH, 0.3 * INCH, 0.1, 20.0, setup.simulation.control_step)
    recording = simulate_rig(setup, reference, closed_loop=True).recording
    late = recording["time [s]"] > SKIP
    speed = np.abs(recording["velocity [m/s]"][late])
    error = recording["position [m]"][late] - recording["reference position [m]"][late]
    rest = speed[speed < AT_REST]
    creep = speed[speed < SLIP]
    return {
        "time slower than 10 µm/s [%]": 100.0 * rest.size / speed.size,
        "median speed of those samples [µm/s]": 1e6 * float(np.median(rest)),
        "time slower than 1 mm/s [%]": 100.0 * creep.size / speed.size,
        "creep below 1 mm/s, quartiles [mm/s]": 1e3 * np.percentile(creep, [25, 50, 75]),
        "tracking RMSE [mm]": 1e3 * float(np.sqrt(np.mean(error**2))),
    }


def main() -> None:
    for model in ("stribeck_tanh", "lugre"):
        print(f"{model}:")
        for name, value in measure(model).items():
            shown = np.array2string(np.asarray(value), precision=3, floatmode="maxprec")
            print(f"  {name}: {shown}")


if __name__ == "__main__":
    main()
