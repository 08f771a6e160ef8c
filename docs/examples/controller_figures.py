"""Measure the controller-identification figures of docs/analysis.md ("Controller").

``recovery``
    Closed-loop step trains of thesis-rig (0.4, 1.3, 0.7, 1.1 in, one second each, the
    data of tests/identification/test_controller_fit.py) with two known gain sets, with
    and without a 10 ms measurement delay, at 1 kHz and decimated to 500 Hz: the errors of
    both methods, their standard errors, the filter and the delay found; then the
    command method with 20 mV of white noise on the command and output error with 10 µm
    on the position (seeds 4 and 11).
``rate``
    The 500 Hz recordings without delay fitted with the lag held at one whole sample
    (2 ms, what a search in samples could give) against the default search in control
    steps (1 ms, half a sample).
``lab``
    The demo's stand-in lab data (`pneumaquad.demo.reports`: the closed-loop step train
    of thesis-rig with LuGre friction, 20 µm position noise, a 20 ms time shift), written
    to a temporary folder and read through its mapping: the command method, and output
    error with thesis-rig's Stribeck-tanh friction and with LuGre.

    .venv/bin/python docs/examples/controller_figures.py recovery rate lab
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from pneumaquad.demo.reports import _STEP_LEVELS, write_lab_style_csv
from pneumaquad.identification import fit_controller
from pneumaquad.identification.controller_data import GAIN_KEYS
from pneumaquad.io.measured import load_mapping, read_measured
from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

INCH = 0.0254
LEVELS = (0.4 * INCH, 1.3 * INCH, 0.7 * INCH, 1.1 * INCH)
GAIN_SETS = {"130/150/4": (130.0, 150.0, 4.0), "250/60/2.5": (250.0, 60.0, 2.5)}
THESIS_RIG_GAINS = (300.0, 100.0, 3.0)


def recording(gains, delay_ms: int, decimation: int) -> dict[str, np.ndarray]:
    kp, ki, kd = gains
    setup = load_rig("thesis-rig", [
        f'controller.proportional_gain="{kp} V/m"',
        f'controller.integral_gain="{ki} V/(m*s)"',
        f'controller.derivative_gain="{kd} V*s/m"',
        f'controller.measurement_delay="{delay_ms} ms"'])
    reference = signals.step_train(LEVELS, 1.0, setup.simulation.control_step)
    rows = simulate_rig(setup, reference, closed_loop=True).recording
    return {name: column[decimation - 1::decimation] for name, column in rows.items()}


def line(label: str, fit, truth, seconds: float) -> str:
    errors = np.array(fit.gains()) / np.array(truth) - 1.0
    standard = np.array([fit.fit.standard_errors[key] for key in GAIN_KEYS]) / np.array(truth)
    return (f"| {label} | " + " | ".join(f"{e:+.3%} ({s:.3%})" for e, s in
                                         zip(errors, standard, strict=True))
            + f" | {fit.filter_time_constant * 1e3:.3f} | {fit.measurement_delay * 1e3:g} | "
            f"{seconds:.1f} |")


def header(title: str) -> None:
    print(f"\n{title}\n\n| case | Kp (s.e.) | Ki (s.e.) | Kd (s.e.) | τ_d [ms] | delay [ms] | "
          "time [s] |\n|---|---|---|---|---|---|---|")


def timed(data, setup, **options):
    begun = time.perf_counter()
    fit = fit_controller(data, setup, **options)
    return fit, time.perf_counter() - begun


def recovery() -> None:
    setup = load_rig("thesis-rig")
    for method in ("command", "output-error"):
        header(f"{method} method, noise-free")
        for name, gains in GAIN_SETS.items():
            for delay in (0, 10):
                for rate in (1000, 500):
                    data = recording(gains, delay, 1000 // rate)
                    if method == "output-error":
                        data.pop("command [V]")
                    fit, seconds = timed([data], setup, method=method)
                    print(line(f"{name}, {delay} ms, {rate} Hz", fit, gains, seconds))
    header("with noise")
    gains = GAIN_SETS["250/60/2.5"]
    for rate in (1000, 500):
        data = recording(gains, 10, 1000 // rate)
        data["command [V]"] = data["command [V]"] + np.random.default_rng(4).normal(
            0.0, 0.02, data["command [V]"].size)
        fit, seconds = timed([data], setup, method="command")
        print(line(f"command, 250/60/2.5, 10 ms, {rate} Hz, 20 mV", fit, gains, seconds))
    gains = GAIN_SETS["130/150/4"]
    data = recording(gains, 10, 1)
    data.pop("command [V]")
    data["position [m]"] = data["position [m]"] + np.random.default_rng(11).normal(
        0.0, 10e-6, data["position [m]"].size)
    fit, seconds = timed([data], setup)
    print(line("output error, 130/150/4, 10 ms, 1 kHz, 10 µm", fit, gains, seconds))


def rate() -> None:
    setup = load_rig("thesis-rig")
    header("500 Hz, command method: lag searched in control steps, or held at one sample")
    for name, gains in GAIN_SETS.items():
        data = recording(gains, 0, 2)
        fit, seconds = timed([data], setup, method="command")
        print(line(f"{name}, lag searched ({fit.lag * 1e3:g} ms)", fit, gains, seconds))
        fit, seconds = timed([data], setup, method="command", delay=0.001)
        print(line(f"{name}, lag 2 ms (one sample)", fit, gains, seconds))


def lab() -> None:
    lugre = load_rig("thesis-rig", ['friction.model="lugre"'])
    reference = signals.step_train(_STEP_LEVELS, 2.0, lugre.simulation.control_step)
    rows = simulate_rig(lugre, reference, closed_loop=True).recording
    with tempfile.TemporaryDirectory() as folder:
        csv, mapping = write_lab_style_csv(rows, Path(folder), delay=0.02, with_command=True,
                                           with_reference=True)
        data = read_measured(csv, load_mapping(mapping))
    header("the demo's lab data (true gains 300 V/m, 100 V/(m s), 3 V s/m)")
    fit, seconds = timed([data], load_rig("thesis-rig"))
    print(line("command method", fit, THESIS_RIG_GAINS, seconds))
    for label, setup in (("output error, thesis-rig (Stribeck-tanh)", load_rig("thesis-rig")),
                         ("output error, LuGre friction", lugre)):
        fit, seconds = timed([data], setup, method="output-error")
        print(line(label, fit, THESIS_RIG_GAINS, seconds))
        for note in fit.notes:
            print(f"  note: {note}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("parts", nargs="+", choices=("recovery", "rate", "lab"))
    for part in parser.parse_args().parts:
        {"recovery": recovery, "rate": rate, "lab": lab}[part]()
