"""Synthetic "measured" data for the identification tests.

Recordings come from the rig simulator with known parameters, plus sensor noise of a
realistic size (position 10 um, pressures 0.5 kPa, both one standard deviation, white),
seeded so every run sees the same data.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence

import numpy as np
import pytest

from pneumaquad.params import load_rig
from pneumaquad.params.schema import RigSetup
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

LBF = 4.4482216152605  # N per lbf
POSITION_NOISE = 10e-6  # [m]
PRESSURE_NOISE = 500.0  # [Pa]

#: Friction of the "measured" rig: thesis-rig with F_S, F_C, C_V changed (SI).
TRUE_STATIC = 5.0 * LBF
TRUE_COULOMB = 3.2 * LBF
TRUE_VISCOUS = 70.0
FRICTION_OVERRIDES = (
    f'friction.static_force="{TRUE_STATIC!r} N"',
    f'friction.coulomb_force="{TRUE_COULOMB!r} N"',
    f'friction.viscous_coefficient="{TRUE_VISCOUS!r} N*s/m"',
)
#: Slow steps (clear stiction peaks) and fast ones (wide velocity range) [V].
SLOW_STEPS = (4.5, 4.8, 5.6, 5.75, 6.0)
FAST_STEPS = (3.0, 4.0, 6.5, 7.0, 8.0)

#: Input-pressure cutoffs of the "measured" valve [V] (thesis-rig: +-1.25 / -+0.75).
TRUE_CUTOFFS = {1: (-1.1, 0.9), 2: (1.0, -0.6)}
CUTOFF_OVERRIDES = tuple(
    f'valve.port{port}.{name}="{value!r} V"'
    for port, (high, low) in TRUE_CUTOFFS.items()
    for name, value in (("high_pressure_cutoff", high), ("low_pressure_cutoff", low))
)
#: Centered voltages of the spacer tests [V].
SPACER_VOLTAGES = (-2.0, -1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 0.9, 1.2, 2.0)

#: Factor on each port's area polynomials in the "measured" valve.
TRUE_AREA_FACTORS = {1: 0.75, 2: 1.3}


def add_noise(recording: Mapping[str, np.ndarray], seed: int) -> dict[str, np.ndarray]:
    """A copy with white noise on position and both pressures."""
    rng = np.random.default_rng(seed)
    noisy = {name: np.array(values, dtype=float) for name, values in recording.items()}
    noisy["position [m]"] += rng.normal(0.0, POSITION_NOISE, noisy["position [m]"].size)
    for name in ("cap pressure [Pa]", "rod pressure [Pa]"):
        noisy[name] += rng.normal(0.0, PRESSURE_NOISE, noisy[name].size)
    return noisy


@functools.cache
def rig(*overrides: str) -> RigSetup:
    """thesis-rig with overrides (cached; do not mutate)."""
    return load_rig("thesis-rig", list(overrides))


def step_recording(
    setup: RigSetup, voltage: float, seed: int, step_time: float = 0.5, duration: float = 2.0
) -> dict[str, np.ndarray]:
    """Noisy open-loop step with the thesis protocol (opposite saturation, then the step)."""
    valve = setup.actuator.valve
    command = signals.thesis_step_command(
        voltage,
        valve.offset_voltage,
        valve.min_voltage,
        valve.max_voltage,
        setup.simulation.control_step,
        step_time,
        duration,
    )
    return add_noise(simulate_rig(setup, command, False).recording, seed)


def spacer_recording(setup: RigSetup, centered: Sequence[float], hold: float, seed: int):
    """Noisy fixed-piston staircase through the centered voltages, ``hold`` s each."""
    count = round(hold / setup.simulation.control_step)
    levels = [setup.actuator.valve.offset_voltage + value for value in centered]
    command = np.concatenate([signals.constant(level, count) for level in levels])
    return add_noise(simulate_rig(setup, command, False).recording, seed)


def scaled_polynomial_overrides(base: RigSetup, factors: Mapping[int, float]) -> tuple[str, ...]:
    """Overrides multiplying each port's area polynomials by a factor."""
    items = []
    for port, factor in factors.items():
        valve_port = getattr(base.actuator.valve, f"port{port}")
        for side in ("area_positive", "area_negative"):
            values = ", ".join(repr(factor * c) for c in getattr(valve_port, side))
            items.append(f"valve.port{port}.{side}=[{values}]")
    return tuple(items)


@pytest.fixture(scope="session")
def friction_rig() -> RigSetup:
    """The "measured" rig of the friction tests."""
    return rig(*FRICTION_OVERRIDES)


@pytest.fixture(scope="session")
def friction_steps(friction_rig: RigSetup) -> dict[float, dict[str, np.ndarray]]:
    """Noisy step recordings at SLOW_STEPS + FAST_STEPS, by command voltage."""
    voltages = SLOW_STEPS + FAST_STEPS
    return {
        voltage: step_recording(friction_rig, voltage, seed=index)
        for index, voltage in enumerate(voltages)
    }


@pytest.fixture(scope="session")
def spacer_rig() -> RigSetup:
    """The "measured" rig of the valve tests, piston held by the spacer."""
    return rig(*CUTOFF_OVERRIDES, "rig.spacer=true")


@pytest.fixture(scope="session")
def area_rig() -> RigSetup:
    """The "measured" rig of the equivalent-area tests: polynomials scaled per port."""
    return rig(*scaled_polynomial_overrides(rig(), TRUE_AREA_FACTORS))
