"""Component cost table of the rig model, the analogue of thesis Table 3 (section 5.5.3).

Daepp timed the Simulink target's task execution time (TET) with components removed one
at a time. Here the compiled fixed-step rig loop (PID + rig kernel + recording row,
:func:`pneumaquad.rig.simulate.run_rig_chunk`) is timed per 1 ms control step for:

1. complete model (PID, underlapped valve, Stribeck-tanh, as the parameter set ships);
2. no controller (open loop, replaying the PID commands of the complete run);
3. simple friction (``friction.model="viscous"``);
4. simple valve (``valve.model="simple"``: linear area, plain supply/exhaust);
5. simple valve, area part only: the polynomials overridden to the simple valve's linear
   cd·A, tanh input pressures kept;
6. simple valve, pressure part only: the tanh cutoffs moved to ±1 µV around the offset
   (input pressure = supply or exhaust), polynomial areas kept.

Cases 5 and 6 are parameter overrides of the underlapped kernel, which still evaluates
the polynomial and the tanh (there is no parameter that removes one of the two parts);
they measure the change of flow regimes, not removed arithmetic. Repeats are interleaved
across cases so that slow drifts of the machine hit all alike.
"""

from __future__ import annotations

import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from pneumaquad.params import RigSetup, load_rig
from pneumaquad.params.conversions import METRE_PER_INCH
from pneumaquad.rig.model import rig_bank
from pneumaquad.rig.signals import sine
from pneumaquad.rig.simulate import RIG_COLUMNS, delay_steps, new_rows, run_rig_chunk

__all__ = [
    "THESIS_TABLE_3",
    "CostCase",
    "CostRow",
    "CostTable",
    "cost_cases",
    "measure_cost_table",
    "time_rig_run",
]

#: Thesis Table 3, Gamma joint: case → (average TET [µs], % reduction). "no controller" is
#: against the open-loop complete model (37.260 µs), the rest against 37.498 µs.
THESIS_TABLE_3: dict[str, tuple[float, float | None]] = {
    "complete model": (37.498, None),
    "no controller": (36.819, 1.2),
    "simple friction (viscous)": (33.255, 11.3),
    "simple valve": (28.471, 24.1),
    "simple valve: area part only": (32.728, 12.7),
    "simple valve: pressure part only": (34.525, 7.9),
}


@dataclass(frozen=True)
class CostCase:
    """One case: its name, the parameter overrides, loop mode and how it was made."""

    name: str
    overrides: tuple[str, ...]
    closed_loop: bool
    how: str


@dataclass(frozen=True)
class CostRow:
    """Timing of one case [µs per 1 ms control step].

    ``change_percent`` is 100·(mean − complete mean)/complete mean: negative is faster
    (the thesis printed the reduction, i.e. minus this). ``thesis_us`` and
    ``thesis_reduction_percent`` are Table 3's figures; ``rms_error`` [m] is the case's
    tracking error of the reference (a sanity figure: a broken case would show).
    """

    case: str
    how: str
    mean_us: float
    std_us: float
    min_us: float
    change_us: float
    change_percent: float
    thesis_us: float
    thesis_reduction_percent: float | None
    rms_error: float


@dataclass(frozen=True)
class CostTable:
    """A measured cost table and the conditions it was measured under."""

    rows: list[CostRow]
    parameter_set: str
    steps: int
    control_step: float
    substeps: int
    repeats: int
    machine: str


def cost_cases(setup: RigSetup) -> list[CostCase]:
    """The six cases of the module docstring for an (underlapped) rig setup.

    Parameters
    ----------
    setup : RigSetup
        The complete model (its valve parameters are kept; the cases switch parts off).
    """
    return [
        CostCase("complete model", (), True, "parameter set as shipped, closed loop"),
        CostCase(
            "no controller", (), False, "open loop, replaying the PID commands of the complete run"
        ),
        CostCase(
            "simple friction (viscous)",
            ('friction.model="viscous"',),
            True,
            'friction.model="viscous" (b·v)',
        ),
        CostCase(
            "simple valve",
            ('valve.model="simple"',),
            True,
            'valve.model="simple": linear area, plain supply/exhaust pressures',
        ),
        CostCase(
            "simple valve: area part only",
            ('valve.area_curve="linear"',),
            True,
            'valve.area_curve="linear": the simple valve\'s linear cd·A; tanh pressures kept',
        ),
        CostCase(
            "simple valve: pressure part only",
            ('valve.input_pressure="switched"',),
            True,
            'valve.input_pressure="switched": plain supply/exhaust; polynomial areas kept',
        ),
    ]


def time_rig_run(
    setup: RigSetup, signal: np.ndarray, closed_loop: bool
) -> tuple[float, np.ndarray]:
    """One call of the compiled rig loop over ``signal``: (seconds, recorded rows)."""
    bank = rig_bank(setup)
    records, rows = new_rows(signal.shape[0], 1)
    signals = np.ascontiguousarray(signal, dtype=float).reshape(1, -1)
    sim = setup.simulation
    delays = np.array([delay_steps(setup)], dtype=np.int64)
    start_positions = bank.state["position"].copy()
    start = time.perf_counter()
    run_rig_chunk(bank.actuator_arrays, bank.controller_arrays, closed_loop, signals, 0,
                  signal.shape[0], sim.control_step, sim.substeps, records, delays,
                  start_positions)
    return time.perf_counter() - start, rows[0]


def _machine() -> str:
    return (
        f"{platform.processor() or platform.machine()}, Python "
        f"{platform.python_version()}, numba {numba.__version__}, numpy {np.__version__}"
    )


def measure_cost_table(
    parameter_set: str = "thesis-rig",
    duration: float = 4.0,
    repeats: int = 15,
    amplitude: float = 0.4 * METRE_PER_INCH,
    frequency: float = 0.5,
    progress: Callable[[int, int], None] | None = None,
) -> CostTable:
    """Time the six cases on a closed-loop sine of the rig.

    Parameters
    ----------
    parameter_set : str
        Rig parameter set (name or TOML path) with an underlapped valve.
    duration : float
        Simulated time per run [s].
    repeats : int
        Timed repeats per case (≥ 2), interleaved across cases.
    amplitude, frequency : float
        Sine about half stroke [m], [Hz].
    progress : callable, optional
        Called with (repeats done, repeats).

    Returns
    -------
    CostTable
    """
    if repeats < 2:
        raise ValueError(f"repeats must be at least 2, got {repeats}")
    base = load_rig(parameter_set)
    dt = base.simulation.control_step
    reference = sine(base.actuator.cylinder.stroke / 2, amplitude, frequency, duration, dt)
    cases = cost_cases(base)
    setups = {c.name: load_rig(parameter_set, list(c.overrides)) for c in cases}
    _, complete = time_rig_run(base, reference, True)  # compiles/loads, gives the replay
    replay = complete[:, RIG_COLUMNS.index("command [V]")].copy()
    signals = {c.name: reference if c.closed_loop else replay for c in cases}
    position = RIG_COLUMNS.index("position [m]")
    errors = {}
    for case in cases:  # warm-up and a sanity figure per case
        _, rows = time_rig_run(setups[case.name], signals[case.name], case.closed_loop)
        errors[case.name] = float(np.sqrt(np.mean((rows[:, position] - reference) ** 2)))
    samples: dict[str, list[float]] = {c.name: [] for c in cases}
    for done in range(repeats):
        for case in cases:
            seconds, _ = time_rig_run(setups[case.name], signals[case.name], case.closed_loop)
            samples[case.name].append(seconds / reference.shape[0] * 1e6)
        if progress is not None:
            progress(done + 1, repeats)
    complete_mean = statistics.fmean(samples["complete model"])
    rows_out = []
    for case in cases:
        mean = statistics.fmean(samples[case.name])
        thesis_us, thesis_reduction = THESIS_TABLE_3[case.name]
        rows_out.append(
            CostRow(
                case.name,
                case.how,
                mean,
                statistics.stdev(samples[case.name]),
                min(samples[case.name]),
                mean - complete_mean,
                100.0 * (mean - complete_mean) / complete_mean,
                thesis_us,
                thesis_reduction,
                errors[case.name],
            )
        )
    return CostTable(
        rows_out,
        base.actuator.meta.name,
        int(reference.shape[0]),
        dt,
        base.simulation.substeps,
        repeats,
        _machine(),
    )
