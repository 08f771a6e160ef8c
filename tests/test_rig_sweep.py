"""N rigs in one compiled call: each rig's recording is bit-identical to its run alone."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.params import load_rig
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import RigDivergedError, simulate_rig, simulate_rigs

STEPS = 1500


def _same(together, alone) -> None:
    assert list(together.recording) == list(alone.recording)
    for name, column in alone.recording.items():
        assert np.array_equal(together.recording[name], column, equal_nan=True), name


def test_closed_loop_sweep_of_supply_pressures_equals_separate_runs() -> None:
    setups = [load_rig("thesis-rig", [f'supply.supply_pressure="{psig} psig"'])
              for psig in (35, 50.3, 65)]
    dt = setups[0].simulation.control_step
    references = np.array([signals.sine(0.022, amplitude, 1.0, STEPS * dt, dt)
                           for amplitude in (0.006, 0.01, 0.014)])
    together = simulate_rigs(setups, references, closed_loop=True, chunk_steps=400)
    for setup, reference, result in zip(setups, references, together, strict=True):
        _same(result, simulate_rig(setup, reference, closed_loop=True))
    finals = [result.recording["cap pressure [Pa]"][-1] for result in together]
    assert len(set(finals)) == 3  # the rigs differ


def test_open_loop_rigs_with_their_own_tanks_and_loads_equal_separate_runs() -> None:
    tank = ['supply.model="tank"', 'supply.tank_volume="0.5 L"',
            'supply.tank_initial_pressure="600 kPa"', 'supply.tank_temperature="293 K"']
    setups = [load_rig("thesis-rig", tank),
              load_rig("thesis-rig", [*tank, 'rig.load_mass="3 kg"', 'friction.model="lugre"']),
              load_rig("thesis-rig", ["rig.spacer=true"])]
    commands = np.array([np.full(STEPS, 6.0), np.full(STEPS, 4.2),
                         np.linspace(4.0, 6.0, STEPS)])
    together = simulate_rigs(setups, commands, closed_loop=False)
    for setup, command, result in zip(setups, commands, together, strict=True):
        _same(result, simulate_rig(setup, command, closed_loop=False))
    tanks = [result.recording["tank pressure [Pa]"][-1] for result in together[:2]]
    assert tanks[0] != tanks[1]  # each rig draws from its own tank


def test_one_setup_for_every_rig() -> None:
    setup = load_rig("thesis-rig")
    commands = np.array([np.full(200, 4.5), np.full(200, 5.5)])
    first, second = simulate_rigs(setup, commands, closed_loop=False)
    _same(second, simulate_rig(setup, commands[1], closed_loop=False))
    assert first.recording["position [m]"][-1] != second.recording["position [m]"][-1]


def test_rigs_run_together_must_share_their_step() -> None:
    setups = [load_rig("thesis-rig"), load_rig("thesis-rig", ["simulation.substeps=10"])]
    with pytest.raises(ValueError, match="substeps"):
        simulate_rigs(setups, np.zeros((2, 10)), closed_loop=False)
    with pytest.raises(ValueError, match="rigs, steps"):
        simulate_rigs(setups[0], np.zeros(10), closed_loop=False)
    with pytest.raises(ValueError, match="3 signal rows for 2 setups"):
        simulate_rigs(setups[:1] * 2, np.zeros((3, 10)), closed_loop=False)


def test_adaptive_rigs_run_one_after_the_other() -> None:
    setup = load_rig("thesis-rig", ['simulation.integrator="radau"'])
    commands = np.full((2, 20), 5.5)
    results = simulate_rigs(setup, commands, closed_loop=False)
    assert [r.integrator for r in results] == ["radau", "radau"]
    _same(results[1], simulate_rig(setup, commands[1], closed_loop=False))


def test_a_diverging_rig_is_named() -> None:
    good = load_rig("thesis-rig")
    bad = good.model_copy(update={"rig": good.rig.model_copy(update={"gravity": 1e300})})
    with pytest.raises(RigDivergedError, match="rig 1 of the simulation stopped") as stopped:
        simulate_rigs([good, bad], np.full((2, 100), 6.0), closed_loop=False)
    assert stopped.value.rig == 1
