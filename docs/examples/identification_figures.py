"""Measure the valve-identification figures of docs/analysis.md ("Valve fits").

Every "lab" recording here is simulated with thesis-rig (its parameters are the truth the
fits should give back), as in tests/identification:

``timebase``
    Steps to 6 V and 4 V (centered +0.75 and -1.25 V) of a valve whose area polynomials
    are thesis-rig's times 0.75 (port 1) and 1.3 (port 2), recorded at 500 Hz, 1 kHz and
    2 kHz, without noise and with 0.5 kPa / 10 µm noise (seed 70, the tests' data):
    fitted / true area per port and the fit's pressure and position RMSE.
``temperature``
    Steps after the thesis protocol's 5 s hold at the opposite saturation, centered
    -3 ... -0.75 V and +0.75 ... +3 V, noise-free: the chamber temperatures before the
    step and fitted / true area per port when the fit assumes the supply temperature and
    when it simulates the hold (``start_temperature="hold"``).
``sweeps``
    Every four-voltage spacer sweep (ascending, each voltage held 5 s, no noise) drawn
    from 15 held voltages, centered -1.75 ... +1.75 V in 0.25 V steps (1365 sweeps), with
    ``--noise`` Pa of white noise on both pressures (seed: the sweep's index):
    per port, the fits with a cutoff more than 0.05 V off, and which of the fit's checks
    flag them (fewer than two points in the transition; a cutoff standard error above
    0.05 V or infinite); then the cap pressure's drift over the averaged tail at +0.25 V
    with 3 s and 5 s holds, over the sweeps that hold +0.25 V.

    .venv/bin/python docs/examples/identification_figures.py timebase temperature
    .venv/bin/python docs/examples/identification_figures.py sweeps --noise 500
"""

from __future__ import annotations

import argparse
import itertools

import numpy as np

from pneumaquad.core.valve_fit import evaluate_equivalent_area
from pneumaquad.identification import equivalent_area_for_step, input_pressure_curves
from pneumaquad.identification.input_pressure import steady_state_points
from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

POSITION_NOISE, PRESSURE_NOISE = 10e-6, 500.0  # [m], [Pa], one standard deviation
AREA_FACTORS = {1: 0.75, 2: 1.3}
#: thesis-rig's cutoffs (high, low) [V, centered] per port.
TRUE_CUTOFFS = {1: (-1.25, 0.75), 2: (1.25, -0.75)}
SWEEP_VOLTAGES = np.linspace(-1.75, 1.75, 15)  # centered [V]
WRONG = 0.05  # [V]


def add_noise(recording, seed: int):
    rng = np.random.default_rng(seed)
    noisy = {name: np.array(values, dtype=float) for name, values in recording.items()}
    noisy["position [m]"] += rng.normal(0.0, POSITION_NOISE, noisy["position [m]"].size)
    for name in ("cap pressure [Pa]", "rod pressure [Pa]"):
        noisy[name] += rng.normal(0.0, PRESSURE_NOISE, noisy[name].size)
    return noisy


def scaled_area_overrides(base, factors) -> list[str]:
    items = []
    for port, factor in factors.items():
        valve_port = getattr(base.actuator.valve, f"port{port}")
        for side in ("area_positive", "area_negative"):
            values = ", ".join(repr(factor * c) for c in getattr(valve_port, side))
            items.append(f"valve.port{port}.{side}=[{values}]")
    return items


def true_area(setup, port: int, centered: float) -> float:
    valve_port = getattr(setup.actuator.valve, f"port{port}")
    return float(
        evaluate_equivalent_area(valve_port.area_negative, valve_port.area_positive, centered)
    )


def step(setup, voltage: float, hold: float, after: float):
    valve = setup.actuator.valve
    command = signals.thesis_step_command(
        voltage,
        valve.offset_voltage,
        valve.min_voltage,
        valve.max_voltage,
        setup.simulation.control_step,
        hold,
        hold + after,
    )
    return simulate_rig(setup, command, False).recording


def timebase() -> None:
    base = load_rig("thesis-rig")
    print("time base: rate, centered, noise, fitted/true port 1, port 2, RMSE pressure, position")
    for rate in (500, 1000, 2000):
        control_step = "0.5 ms" if rate == 2000 else "1 ms"
        truth = load_rig(
            "thesis-rig",
            [
                *scaled_area_overrides(base, AREA_FACTORS),
                f'simulation.control_step="{control_step}"',
            ],
        )
        for voltage in (6.0, 4.0):
            centered = voltage - base.actuator.valve.offset_voltage
            recording = step(truth, voltage, 0.5, 0.7)
            if rate == 500:  # every other 1 kHz sample, the step kept on the grid
                recording = {name: values[1::2] for name, values in recording.items()}
            for label, data in (("none", recording), ("noisy", add_noise(recording, 70))):
                fit = equivalent_area_for_step(base, data)
                ratios = [fit.areas[p] / true_area(truth, p, centered) for p in (1, 2)]
                print(
                    f"  {rate:4d} Hz {centered:+.2f} V {label:5s} {ratios[0]:.5f} "
                    f"{ratios[1]:.5f}  {fit.pressure_rmse:6.1f} Pa "
                    f"{1e6 * fit.position_rmse:5.2f} µm"
                )


def temperature() -> None:
    base = load_rig("thesis-rig")
    offset = base.actuator.valve.offset_voltage
    print("start temperature (5 s hold): centered, T cap/rod before [K], area/true port 1, 2")
    for centered in (-3.0, -2.0, -1.25, -0.75, 0.75, 1.25, 2.0, 3.0):
        full = step(base, offset + centered, 5.0, 0.8)
        before = int(np.argmax(np.abs(np.diff(full["command [V]"])) > 0.05))
        temperatures = (full["cap temperature [K]"][before], full["rod temperature [K]"][before])
        lab = {
            name: full[name]
            for name in (
                "time [s]",
                "command [V]",
                "position [m]",
                "cap pressure [Pa]",
                "rod pressure [Pa]",
            )
        }
        line = f"  {centered:+.2f} V ({temperatures[0]:.0f}, {temperatures[1]:.0f})"
        for source in ("supply", "hold"):
            fit = equivalent_area_for_step(base, lab, start_temperature=source)
            ratios = [100 * (fit.areas[p] / true_area(base, p, centered) - 1) for p in (1, 2)]
            line += f"  {source}: {ratios[0]:+.2f} % {ratios[1]:+.2f} %"
            if source == "hold":
                line += f" (hold: {fit.start_temperatures[0]:.0f}, {fit.start_temperatures[1]:.0f})"
        print(line)


def sweep_recording(setup, centered, hold: float):
    count = round(hold / setup.simulation.control_step)
    offset = setup.actuator.valve.offset_voltage
    command = np.concatenate([signals.constant(offset + value, count) for value in centered])
    return simulate_rig(setup, command, False).recording


def sweeps(pressure_noise: float = 0.0) -> None:
    setup = load_rig("thesis-rig", ["rig.spacer=true"])
    tally = {
        port: {"wrong": 0, "transition": 0, "error": 0, "any": 0, "false": 0} for port in (1, 2)
    }
    drifts = {3.0: [], 5.0: []}
    combinations = list(itertools.combinations(SWEEP_VOLTAGES, 4))
    for index, centered in enumerate(combinations):
        recording = sweep_recording(setup, centered, 5.0)
        noisy = dict(recording)
        rng = np.random.default_rng(index)
        for name in ("cap pressure [Pa]", "rod pressure [Pa]"):
            noisy[name] = recording[name] + rng.normal(0.0, pressure_noise, recording[name].size)
        curves = input_pressure_curves([noisy], setup)
        for port, fit in curves.fits.items():
            high, low = TRUE_CUTOFFS[port]
            off = max(
                abs(fit.value("high_pressure_cutoff") - high),
                abs(fit.value("low_pressure_cutoff") - low),
            )
            transition = any("transition" in problem for problem in fit.problems)
            error = any("standard error" in problem for problem in fit.problems)
            counts = tally[port]
            if off > WRONG:
                counts["wrong"] += 1
                counts["transition"] += transition
                counts["error"] += error
                counts["any"] += fit.failed
            elif fit.failed:
                counts["false"] += 1
        if np.any(np.isclose(centered, 0.25)):
            drifts[5.0].append(_drift_at(recording, setup))
            drifts[3.0].append(_drift_at(sweep_recording(setup, centered, 3.0), setup))
    print(
        f"{len(combinations)} four-voltage sweeps from {SWEEP_VOLTAGES.size} voltages, "
        f"pressure noise {pressure_noise:g} Pa:"
    )
    for port, counts in tally.items():
        print(
            f"  port {port}: {counts['wrong']} fits more than {WRONG} V off; flagged by the "
            f"transition rule {counts['transition']}, by the standard error {counts['error']}, "
            f"by any check {counts['any']}; correct fits flagged {counts['false']}"
        )
    for hold, values in drifts.items():
        values = np.abs(values) / 1e3
        print(
            f"  cap drift at +0.25 V, {hold:.0f} s holds ({values.size} sweeps): "
            f"{values.min():.2f}-{values.max():.2f} kPa"
        )


def _drift_at(recording, setup) -> float:
    points = steady_state_points([recording], setup)
    index = int(np.argmin(np.abs(points.centered_voltage - 0.25)))
    return float(points.cap_drift[index])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("section", nargs="+", choices=("timebase", "temperature", "sweeps"))
    parser.add_argument(
        "--noise", type=float, default=0.0, help="sweeps: white pressure noise [Pa], seeded"
    )
    args = parser.parse_args()
    sections = {
        "timebase": timebase,
        "temperature": temperature,
        "sweeps": lambda: sweeps(args.noise),
    }
    for name in args.section:
        sections[name]()


if __name__ == "__main__":
    main()
