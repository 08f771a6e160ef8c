"""The rig controller's measurement delay: the PID sees the position of d steps earlier."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.core.control.pid import new_pid_state, pid_update
from pneumaquad.params import ParameterError, load_rig, load_robot
from pneumaquad.rig import signals
from pneumaquad.rig.model import rig_controller_gains, rig_start
from pneumaquad.rig.simulate import delay_steps, simulate_rig, simulate_rigs


def _commands_from_positions(setup, reference: np.ndarray, position: np.ndarray,
                             delay: int) -> np.ndarray:
    """The PID's commands replayed from a recording: at step k it sees the position of
    row k - delay - 1 (the start position before the first rows)."""
    gains = rig_controller_gains(setup)
    state = new_pid_state()
    start = rig_start(setup)[0]
    dt = setup.simulation.control_step
    commands = np.empty(reference.size)
    for k in range(reference.size):
        row = k - delay - 1
        measured = position[row] if row >= 0 else start
        commands[k] = pid_update(gains, state, reference[k], measured, dt)
    return commands


def _steps(setup, steps: int) -> np.ndarray:
    inch = 0.0254
    dwell = steps * setup.simulation.control_step / 3
    return signals.step_train([0.6 * inch, 1.3 * inch, 0.9 * inch], dwell,
                              setup.simulation.control_step)


@pytest.mark.parametrize("delay", ["0 ms", "10 ms", "3.4 ms"])
def test_the_pid_sees_the_position_of_the_delay_earlier(delay: str) -> None:
    setup = load_rig("thesis-rig", [f'controller.measurement_delay="{delay}"'])
    reference = _steps(setup, 1500)
    recording = simulate_rig(setup, reference, closed_loop=True, chunk_steps=400).recording
    steps = delay_steps(setup)
    assert steps == {"0 ms": 0, "10 ms": 10, "3.4 ms": 3}[delay]
    replayed = _commands_from_positions(setup, reference, recording["position [m]"], steps)
    assert np.array_equal(replayed, recording["command [V]"])


def test_a_delay_changes_the_response_and_rigs_with_different_delays_run_together() -> None:
    setups = [load_rig("thesis-rig", [f'controller.measurement_delay="{ms} ms"'])
              for ms in (0, 10, 30)]
    reference = _steps(setups[0], 1200)
    together = simulate_rigs(setups, np.tile(reference, (3, 1)), closed_loop=True,
                             chunk_steps=300)
    for setup, result in zip(setups, together, strict=True):
        alone = simulate_rig(setup, reference, closed_loop=True).recording
        for name, column in alone.items():
            assert np.array_equal(result.recording[name], column, equal_nan=True), name
    positions = [result.recording["position [m]"] for result in together]
    assert not np.array_equal(positions[0], positions[1])
    # a longer delay overshoots more on the first step down
    overshoot = [reference[0] - position[:400].min() for position in positions]
    assert overshoot[2] > overshoot[0]


def test_the_adaptive_reference_honours_the_delay() -> None:
    setup = load_rig("thesis-rig", ['controller.measurement_delay="5 ms"',
                                    'simulation.integrator="radau"'])
    reference = _steps(setup, 150)
    recording = simulate_rig(setup, reference, closed_loop=True).recording
    replayed = _commands_from_positions(setup, reference, recording["position [m]"], 5)
    assert np.array_equal(replayed, recording["command [V]"])


def test_the_delay_has_a_range() -> None:
    with pytest.raises(ParameterError, match=r"controller\.measurement_delay.*at most 0\.1 s"):
        load_rig("thesis-rig", ['controller.measurement_delay="0.2 s"'])
    with pytest.raises(ParameterError, match=r"controller\.measurement_delay"):
        load_rig("thesis-rig", ['controller.measurement_delay="-1 ms"'])


def test_the_robot_controllers_have_no_delay_key() -> None:
    with pytest.raises(ParameterError, match="measurement_delay"):
        load_robot("crr-quadruped", ['controller.alpha.measurement_delay="10 ms"'])
