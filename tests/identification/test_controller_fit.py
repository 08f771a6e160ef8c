"""Controller identification: known gains back from simulated closed-loop recordings.

Recordings of the thesis rig in closed loop with known gains (two sets, with and without
a 10 ms measurement delay), at the simulator's 1 kHz and decimated to 500 Hz, are fitted
by both methods; ``pytest -s`` prints the errors. Measured (4 s step trains): the command
method within 0.02 % at 1 kHz and 0.9 % at 500 Hz (Ki of the second set), the delay
exactly; output error exact (to 1e-6) with the same plant, within 0.1 % with 10 µm
position noise.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from pneumaquad.identification import IdentificationError, fit_controller
from pneumaquad.identification.controller_data import FILTER_KEY, GAIN_KEYS
from pneumaquad.identification.report import write_parameter_file
from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

INCH = 0.0254
#: Reference levels of the step train [m], one second each.
LEVELS = (0.4 * INCH, 1.3 * INCH, 0.7 * INCH, 1.1 * INCH)
GAIN_SETS = {"slow": (130.0, 150.0, 4.0), "stiff": (250.0, 60.0, 2.5)}
FILTER = 5e-3  # thesis-rig's derivative filter [s]


@functools.cache
def recording(gains: str, delay_ms: int, decimation: int = 1,
              levels: tuple[float, ...] = LEVELS) -> dict[str, np.ndarray]:
    """A closed-loop step train of thesis-rig with the named gains and delay, every
    ``decimation``-th row (do not mutate)."""
    kp, ki, kd = GAIN_SETS[gains]
    setup = load_rig("thesis-rig", [
        f'controller.proportional_gain="{kp} V/m"',
        f'controller.integral_gain="{ki} V/(m*s)"',
        f'controller.derivative_gain="{kd} V*s/m"',
        f'controller.measurement_delay="{delay_ms} ms"',
    ])
    reference = signals.step_train(levels, 1.0, setup.simulation.control_step)
    rows = simulate_rig(setup, reference, closed_loop=True).recording
    return {name: column[decimation - 1::decimation] for name, column in rows.items()}


def errors(fit, gains: str) -> np.ndarray:
    """Relative errors of Kp, Ki, Kd [-]."""
    return np.array(fit.gains()) / np.array(GAIN_SETS[gains]) - 1.0


def standard_errors(fit, gains: str) -> np.ndarray:
    """Relative standard errors of Kp, Ki, Kd [-]."""
    return np.array([fit.fit.standard_errors[key] for key in GAIN_KEYS]) / np.array(
        GAIN_SETS[gains])


def report(label: str, fit, gains: str) -> None:
    print(f"{label}: Kp, Ki, Kd " + ", ".join(f"{e:+.4%}" for e in errors(fit, gains))
          + " (s.e. " + ", ".join(f"{s:.3%}" for s in standard_errors(fit, gains)) + "), "
          f"τ_d {fit.filter_time_constant * 1e3:.4g} ms, delay "
          f"{fit.measurement_delay * 1e3:g} ms")


CASES = [(gains, delay, rate) for gains in GAIN_SETS for delay in (0, 10)
         for rate in (1000, 500)]


@pytest.mark.parametrize(("gains", "delay", "rate"), CASES)
def test_the_command_method_recovers_known_gains(gains: str, delay: int, rate: int) -> None:
    data = recording(gains, delay, 1000 // rate)
    fit = fit_controller([data], load_rig("thesis-rig"))
    report(f"command, {gains} gains, {delay} ms, {rate} Hz", fit, gains)
    assert fit.method == "command" and not fit.failed
    assert np.all(np.abs(errors(fit, gains)) < 0.05)
    assert np.all(np.abs(errors(fit, gains)) < (0.0005 if rate == 1000 else 0.01))
    assert fit.measurement_delay == pytest.approx(delay * 1e-3, abs=1e-9)
    assert fit.filter_fitted and fit.filter_time_constant == pytest.approx(FILTER, rel=0.02)
    assert np.all(np.isfinite(standard_errors(fit, gains)))
    updates = fit.updates()
    assert updates["controller.measurement_delay"] == f"{delay * 1e-3!r} s"
    assert set(updates) == {f"controller.{name}" for name in (
        "proportional_gain", "integral_gain", "derivative_gain",
        "derivative_filter_time_constant", "measurement_delay")}


@pytest.mark.parametrize("rate", [1000, 500])
def test_the_command_method_standard_errors_cover_command_noise(rate: int) -> None:
    data = dict(recording("stiff", 10, 1000 // rate))
    noisy = data["command [V]"] + np.random.default_rng(4).normal(0.0, 0.02, rate * 4)
    data["command [V]"] = noisy
    fit = fit_controller([data], load_rig("thesis-rig"), method="command")
    report(f"command + 20 mV noise, {rate} Hz", fit, "stiff")
    assert np.all(np.abs(errors(fit, "stiff")) < 0.05)
    assert np.all(np.abs(errors(fit, "stiff")) <= 3.0 * standard_errors(fit, "stiff"))
    assert fit.fit.residual_rms == pytest.approx(0.02, rel=0.1)


def _output_error(gains: str, delay: int, rate: int, noise: float = 0.0):
    data = {name: column.copy() for name, column in recording(gains, delay, 1000 // rate).items()
            if name != "command [V]"}
    rng = np.random.default_rng(11)
    data["position [m]"] += rng.normal(0.0, noise, data["position [m]"].size)
    return fit_controller([data], load_rig("thesis-rig"))


FAST_OUTPUT_ERROR = [("slow", 0, 1000), ("stiff", 10, 500)]


@pytest.mark.parametrize(("gains", "delay", "rate"), [
    case if case in FAST_OUTPUT_ERROR else pytest.param(*case, marks=pytest.mark.slow)
    for case in CASES])
def test_output_error_recovers_known_gains(gains: str, delay: int, rate: int) -> None:
    fit = _output_error(gains, delay, rate)
    report(f"output error, {gains} gains, {delay} ms, {rate} Hz", fit, gains)
    assert fit.method == "output error" and not fit.failed
    assert np.all(np.abs(errors(fit, gains)) < 0.05)
    assert np.all(np.abs(errors(fit, gains)) < 1e-4)  # the same plant: exactly
    assert fit.measurement_delay == pytest.approx(delay * 1e-3, abs=1e-9)
    assert fit.filter_time_constant == pytest.approx(FILTER, rel=1e-3)


def test_output_error_with_position_noise_and_its_standard_errors() -> None:
    fit = _output_error("slow", 10, 1000, noise=10e-6)
    report("output error + 10 um noise, 1 kHz", fit, "slow")
    assert np.all(np.abs(errors(fit, "slow")) < 0.05)
    assert np.all(np.abs(errors(fit, "slow")) <= 3.0 * standard_errors(fit, "slow"))
    assert fit.measurement_delay == pytest.approx(0.01)
    assert fit.fit.residual_rms == pytest.approx(10e-6, rel=0.1)
    assert FILTER_KEY in fit.fit.parameters and not fit.notes


def test_a_constant_reference_is_refused() -> None:
    data = dict(recording("slow", 0))
    data["reference position [m]"] = np.full_like(data["time [s]"], 0.02)
    with pytest.raises(IdentificationError, match="reference position is constant"):
        fit_controller([data], load_rig("thesis-rig"))


def test_missing_columns_and_the_command_method_without_a_command() -> None:
    data = dict(recording("slow", 0))
    without_reference = {k: v for k, v in data.items() if k != "reference position [m]"}
    with pytest.raises(IdentificationError, match="lacks the columns"):
        fit_controller([without_reference], load_rig("thesis-rig"))
    without_command = {k: v for k, v in data.items() if k != "command [V]"}
    with pytest.raises(IdentificationError, match="needs the valve command"):
        fit_controller([without_command], load_rig("thesis-rig"), method="command")
    with pytest.raises(IdentificationError, match="expected one of"):
        fit_controller([data], load_rig("thesis-rig"), method="guess")
    with pytest.raises(IdentificationError, match="delay"):
        fit_controller([data], load_rig("thesis-rig"), delay=0.2)


def test_a_given_delay_and_a_held_filter() -> None:
    data = recording("stiff", 10)
    fit = fit_controller([data], load_rig("thesis-rig"), delay=0.01, fit_filter=False)
    assert not fit.delay_fitted and not fit.filter_fitted
    assert FILTER_KEY not in fit.fit.parameters
    assert np.all(np.abs(errors(fit, "stiff")) < 5e-4)
    assert set(fit.updates()) == {"controller.proportional_gain",
                                  "controller.integral_gain", "controller.derivative_gain"}
    wrong = fit_controller([data], load_rig("thesis-rig"), delay=0.0, fit_filter=False)
    assert wrong.fit.residual_rms > 10 * fit.fit.residual_rms


def test_several_recordings_and_a_fitted_offset(tmp_path) -> None:
    first, second = recording("slow", 10), recording("slow", 10, 1, LEVELS[::-1])
    fit = fit_controller([first, second], load_rig("thesis-rig"), fit_offset=True)
    assert fit.fit.n_points > 6000
    assert fit.fit.value("offset_voltage") == pytest.approx(5.25, abs=1e-3)
    assert np.all(np.abs(errors(fit, "slow")) < 5e-4)
    written = write_parameter_file("thesis-rig", fit.updates(), tmp_path / "c.toml",
                                   fits=(fit.fit,))
    controller = load_rig(written).controller
    assert controller.proportional_gain == pytest.approx(130.0, rel=5e-4)
    assert controller.measurement_delay == pytest.approx(0.01)


def test_a_gain_the_data_do_not_determine_fails_its_check() -> None:
    # a PI controller: Kd = 0, so its filter is not determined either
    setup = load_rig("thesis-rig")
    kp, ki, _ = GAIN_SETS["slow"]
    pi = load_rig("thesis-rig", [f'controller.proportional_gain="{kp} V/m"',
                                 f'controller.integral_gain="{ki} V/(m*s)"',
                                 'controller.derivative_gain="0 V*s/m"'])
    reference = signals.step_train(LEVELS, 1.0, pi.simulation.control_step)
    rows = simulate_rig(pi, reference, closed_loop=True).recording
    fit = fit_controller([rows], setup)
    assert fit.failed and any("derivative_gain" in problem for problem in fit.fit.problems)
    assert not fit.filter_fitted and any("derivative filter" in note for note in fit.notes)
    assert fit.gains()[0] == pytest.approx(kp, rel=1e-3)


@pytest.mark.slow
def test_output_error_with_another_plant_says_so() -> None:
    # LuGre friction made the recording, the fit's plant has Stribeck-tanh friction
    kp, ki, kd = GAIN_SETS["slow"]
    lugre = load_rig("thesis-rig", ['friction.model="lugre"',
                                    f'controller.proportional_gain="{kp} V/m"',
                                    f'controller.integral_gain="{ki} V/(m*s)"',
                                    f'controller.derivative_gain="{kd} V*s/m"'])
    reference = signals.step_train(LEVELS, 1.0, lugre.simulation.control_step)
    rows = simulate_rig(lugre, reference, closed_loop=True).recording
    rows.pop("command [V]")
    rows["position [m]"] = rows["position [m]"] + np.random.default_rng(3).normal(
        0.0, 10e-6, rows["position [m]"].size)
    fit = fit_controller([rows], load_rig("thesis-rig"))
    report("output error, LuGre recording, Stribeck-tanh plant", fit, "slow")
    assert any("does not follow the recording" in note for note in fit.notes)
    same = fit_controller([rows], load_rig("thesis-rig", ['friction.model="lugre"']))
    assert np.all(np.abs(errors(same, "slow")) < 0.01)
    assert not any("does not follow" in note for note in same.notes)
