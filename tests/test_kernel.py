"""The compiled multi-actuator kernel: batching, determinism and supply bookkeeping."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import Actuators, actuator_setup
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.layout import SUPPLY_DTYPE, float_view
from pneumaquad.core.physics.friction import FRICTION_STRIBECK_TANH, friction_force

# A mix that exercises every branch the kernel has: both valve models, both flow forms,
# every friction and thermodynamics model, a spool lag.
MIXED = [
    ("crr-alpha", ()),
    ("crr-beta", ('friction.model="lugre"', 'valve.spool_time_constant="4 ms"')),
    ("crr-gamma", ('valve.model="simple"', 'thermodynamics.model="heat_transfer"')),
    ("crr-gamma", ('valve.flow_form="iso6358"', 'friction.model="coulomb_viscous"')),
    (
        "crr-alpha",
        (
            'valve.model="simple"',
            'valve.flow_form="iso6358"',
            'thermodynamics.model="polytropic"',
            'friction.model="viscous"',
        ),
    ),
    ("crr-beta", ("valve.cap_port=1", 'friction.model="coulomb"')),
]


def mixed_actuators():
    return [actuator_setup(name, *overrides) for name, overrides in MIXED]


def drive(actuators, commands, positions, velocities, dt=1e-3, substeps=10):
    """Run a batch over prescribed inputs (steps x N); return states and outputs per step."""
    n = len(actuators)
    strokes = np.array([a.cylinder.stroke for a in actuators])
    acts = Actuators(actuators, positions[0], np.full(n, 2.0e5), np.full(n, 3.0e5))
    states, outputs = [], []
    for k in range(commands.shape[0]):
        step_actuators(
            acts.params,
            acts.state,
            commands[k],
            positions[k],
            velocities[k],
            dt,
            substeps,
            acts.supply,
            acts.outputs,
        )
        states.append(acts.state.copy())
        outputs.append(acts.outputs.copy())
    assert np.all(positions <= strokes)
    return np.array(states), np.array(outputs), acts.supply.copy()


def _floats(array: np.ndarray) -> np.ndarray:
    """A state or output stack as floats; the supply record's fields as a float vector."""
    if array.dtype == SUPPLY_DTYPE:
        return np.array([array[0][name] for name in SUPPLY_DTYPE.names], dtype=float)
    return float_view(array)


def random_inputs(actuators, steps=300, seed=1):
    rng = np.random.default_rng(seed)
    n = len(actuators)
    strokes = np.array([a.cylinder.stroke for a in actuators])
    commands = np.repeat(rng.uniform(0.0, 10.0, size=(steps // 30, n)), 30, axis=0)
    t = np.arange(steps)[:, None] * 1e-3
    phase = rng.uniform(0, 2 * np.pi, n)
    positions = strokes * (0.5 + 0.4 * np.sin(2 * np.pi * 2.0 * t + phase))
    velocities = strokes * 0.4 * 2 * np.pi * 2.0 * np.cos(2 * np.pi * 2.0 * t + phase)
    return commands, positions, velocities


def test_batch_equals_separate_single_calls_bit_for_bit() -> None:
    actuators = mixed_actuators()
    commands, positions, velocities = random_inputs(actuators)
    batch_states, batch_outputs, _ = drive(actuators, commands, positions, velocities)
    for i, actuator in enumerate(actuators):
        states, outputs, _ = drive(
            [actuator], commands[:, i : i + 1], positions[:, i : i + 1], velocities[:, i : i + 1]
        )
        np.testing.assert_array_equal(float_view(batch_states[:, i]), float_view(states[:, 0]))
        np.testing.assert_array_equal(float_view(batch_outputs[:, i]), float_view(outputs[:, 0]))


def test_results_are_deterministic() -> None:
    actuators = mixed_actuators()
    inputs = random_inputs(actuators, seed=7)
    first = drive(actuators, *inputs)
    second = drive(actuators, *inputs)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(_floats(a), _floats(b))
    assert np.all(np.isfinite(float_view(first[0]))) and np.all(np.isfinite(float_view(first[1])))


def test_friction_output_is_the_model_at_the_given_velocity(gamma) -> None:
    actuator = gamma
    f = actuator.friction
    for velocity in (-0.05, -1e-4, 0.0, 2e-4, 0.1):
        acts = Actuators([actuator], [0.02], [2e5], [2e5])
        step_actuators(
            acts.params,
            acts.state,
            np.array([5.25]),
            np.array([0.02]),
            np.array([velocity]),
            1e-3,
            10,
            acts.supply,
            acts.outputs,
        )
        expected = friction_force(
            FRICTION_STRIBECK_TANH,
            velocity,
            0.0,
            f.static_force,
            f.coulomb_force,
            f.viscous_coefficient,
            f.stribeck_velocity,
            f.stribeck_exponent,
            f.tanh_coefficient,
            f.damping_coefficient,
            f.bristle_stiffness,
            f.bristle_damping,
        )
        assert acts.outputs[0]["friction_force"] == pytest.approx(
            expected, rel=1e-12, abs=1e-12
        )
        assert acts.state[0]["position"] == pytest.approx(0.02 + velocity * 1e-3)


def test_mass_bookkeeping_and_shared_tank() -> None:
    """Mean flows integrate to the chamber masses; the tank loses R·T·m/V per kg drawn."""
    overrides = (
        'supply.model="tank"',
        'supply.tank_volume="0.2 L"',
        'supply.tank_initial_pressure="20 bara"',
    )
    actuators = [
        actuator_setup(name, *overrides) for name in ("crr-alpha", "crr-beta", "crr-gamma")
    ]
    commands, positions, velocities = random_inputs(actuators, steps=600, seed=3)
    acts = Actuators(actuators, positions[0], np.full(3, 2.0e5), np.full(3, 3.0e5))
    masses0 = np.column_stack([acts.state["cap_mass"], acts.state["rod_mass"]])
    dt = 1e-3
    flows = np.zeros((3, 2))
    drawn = np.zeros(3)
    for k in range(commands.shape[0]):
        step_actuators(
            acts.params,
            acts.state,
            commands[k],
            positions[k],
            velocities[k],
            dt,
            10,
            acts.supply,
            acts.outputs,
        )
        out = acts.outputs
        flows += np.column_stack([out["cap_mass_flow"], out["rod_mass_flow"]]) * dt
        drawn += acts.outputs["supply_mass_flow"] * dt
    masses = np.column_stack([acts.state["cap_mass"], acts.state["rod_mass"]])
    np.testing.assert_allclose(masses - masses0, flows, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(acts.state["air_consumed"], drawn, rtol=1e-9)
    total = acts.supply[0]["drawn_mass"]
    assert total == pytest.approx(drawn.sum(), rel=1e-12)
    assert total > 0.0
    supply = actuators[0].supply
    expected = supply.tank_initial_pressure - (
        actuators[0].gas.gas_constant * supply.tank_temperature * total / supply.tank_volume
    )
    assert acts.supply[0]["tank_pressure"] == pytest.approx(expected, rel=1e-12)
    assert acts.supply[0]["tank_pressure"] < supply.tank_initial_pressure
