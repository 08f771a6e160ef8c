"""The rig recording, defined once, and what a rig run returns.

:data:`RIG_RECORDING` lists (field of a row record, column header) in column order:
:data:`RIG_ROW_DTYPE` is the row record the compiled :func:`write_row` fills by name from
the rig's kernel records (:mod:`pneumaquad.core.layout`), :data:`RIG_COLUMNS` the headers.
Both integrators of :mod:`pneumaquad.rig.simulate` write rows here, check them for
non-finite values and hand them to the recorder.
"""

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pneumaquad.core.jit import compiled
from pneumaquad.core.layout import SUPPLY_TANK
from pneumaquad.core.pneumatics import supply_pressure_now
from pneumaquad.io.run_folder import RunRecorder
from pneumaquad.params.schema import RigSetup

#: The rig recording, defined once: (field of a row record, column header) in column
#: order. :func:`write_row` fills the fields by name; the headers name the columns.
RIG_RECORDING = (
    ("time", "time [s]"),
    ("command", "command [V]"),
    ("reference", "reference position [m]"),
    ("position", "position [m]"),
    ("velocity", "velocity [m/s]"),
    ("cap_pressure", "cap pressure [Pa]"),
    ("rod_pressure", "rod pressure [Pa]"),
    ("cap_temperature", "cap temperature [K]"),
    ("rod_temperature", "rod temperature [K]"),
    ("cap_mass_flow", "cap mass flow [kg/s]"),
    ("rod_mass_flow", "rod mass flow [kg/s]"),
    ("cap_mass", "cap mass [kg]"),
    ("rod_mass", "rod mass [kg]"),
    ("friction_force", "friction force [N]"),
    ("pneumatic_force", "pneumatic force [N]"),
    ("end_stop_force", "end stop force [N]"),
    ("supply_pressure", "supply pressure [Pa]"),
    ("supply_mass_flow", "supply mass flow [kg/s]"),
    ("air_consumed", "air consumed [kg]"),
    ("tank_pressure", "tank pressure [Pa]"),
    ("net_force", "net force [N]"),
    ("air_consumed_normal_litres", "air consumed [NL]"),
)
RIG_ROW_DTYPE = np.dtype([(field, "f8") for field, _ in RIG_RECORDING])
RIG_COLUMNS = tuple(header for _, header in RIG_RECORDING)
N_COLUMNS = len(RIG_COLUMNS)

#: Normal conditions (DIN 1343) for normal litres: pressure [Pa] and temperature [K].
NORMAL_PRESSURE = 101325.0
NORMAL_TEMPERATURE = 273.15

#: Columns that are NaN by design: the reference of an open-loop run, the tank pressure
#: of an ideal supply.
_REFERENCE_COLUMN = RIG_COLUMNS.index("reference position [m]")
_TANK_COLUMN = RIG_COLUMNS.index("tank pressure [Pa]")


@compiled
def write_row(records, index, sample_time, command, reference, p, s, out, supply):
    """Fill record ``index`` of ``records`` (:data:`RIG_ROW_DTYPE`) from the rig's records
    after a step: parameters ``p``, state ``s``, outputs ``out`` and ``supply``
    (:mod:`pneumaquad.core.layout`)."""
    row = records[index]
    row.time = sample_time
    row.command = command
    row.reference = reference
    row.position = s.position
    row.velocity = s.velocity
    row.cap_pressure = s.cap_pressure
    row.rod_pressure = s.rod_pressure
    row.cap_temperature = out.cap_temperature
    row.rod_temperature = out.rod_temperature
    row.cap_mass_flow = out.cap_mass_flow
    row.rod_mass_flow = out.rod_mass_flow
    row.cap_mass = s.cap_mass
    row.rod_mass = s.rod_mass
    row.friction_force = out.friction_force
    row.pneumatic_force = out.pneumatic_force
    row.end_stop_force = out.end_stop_force
    row.supply_pressure = supply_pressure_now(p, supply)
    row.supply_mass_flow = out.supply_mass_flow
    row.air_consumed = s.air_consumed
    row.tank_pressure = supply.tank_pressure if supply.model == SUPPLY_TANK else math.nan
    # eq 4.1.11 with friction: what accelerates the piston besides gravity and the stops
    row.net_force = out.pneumatic_force - out.friction_force
    normal_density = NORMAL_PRESSURE / (p.gas_constant * NORMAL_TEMPERATURE)
    row.air_consumed_normal_litres = s.air_consumed / normal_density * 1000.0


def new_rows(count: int, rigs: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``count`` zeroed recording rows: the records (:data:`RIG_ROW_DTYPE`) the compiled
    code fills, and the same memory as a ``(count, N_COLUMNS)`` float array; with
    ``rigs``, ``count`` rows of each rig: ``(rigs, count)`` records and a
    ``(rigs, count, N_COLUMNS)`` float array."""
    shape = (count,) if rigs is None else (rigs, count)
    records = np.zeros(shape, RIG_ROW_DTYPE)
    return records, records.view(np.float64).reshape(*shape, N_COLUMNS)




@dataclass
class RigResult:
    """Outcome of a rig run: the recording as columns, and how the run went."""

    recording: dict[str, np.ndarray]
    interrupted: bool
    wall_time: float
    integrator: str


ProgressCallback = Callable[[int, int], None]


class RigDivergedError(RuntimeError):
    """A rig run produced a non-finite value; the rows before it were recorded.

    Attributes
    ----------
    quantity : str
        Recording column (``"cap pressure [Pa]"``) of the first non-finite value.
    time : float
        Sample time of the row holding it [s].
    result : RigResult
        The run up to the last finite row.
    rig : int or None
        Index of the rig among several run together (:func:`pneumaquad.rig.simulate.
        simulate_rigs`); None for a single rig.
    """

    def __init__(self, quantity: str, time: float, result: RigResult,
                 rig: int | None = None) -> None:
        self.quantity = quantity
        self.time = time
        self.result = result
        self.rig = rig
        rows = result.recording["time [s]"]
        kept = (
            f"the recording up to t = {rows[-1]:.6g} s is kept"
            if rows.size
            else "nothing before it was recorded"
        )
        which = "the rig simulation" if rig is None else f"rig {rig} of the simulation"
        super().__init__(
            f"{which} stopped: {quantity} became non-finite at t = {time:.6g} s "
            f"({kept}); the parameters or the command drive the model where it cannot be "
            "integrated; try a smaller simulation.control_step, more simulation.substeps "
            "or other parameter values"
        )


def skipped_columns(setup: RigSetup, closed_loop: bool) -> list[int]:
    """Columns that may hold NaN in this run: the reference of an open-loop run, the tank
    pressure of an ideal supply."""
    skipped = [] if closed_loop else [_REFERENCE_COLUMN]
    if setup.actuator.supply.model != "tank":
        skipped.append(_TANK_COLUMN)
    return skipped


def first_non_finite(rows: np.ndarray, skipped: list[int]) -> tuple[int, int] | None:
    """(row, column) of the first non-finite value of ``rows`` outside ``skipped`` columns.

    Rows are searched in order, and within the first bad row the first column in
    :data:`RIG_COLUMNS` order is named; ``None`` when every value is finite.
    """
    bad = ~np.isfinite(rows)
    bad[:, skipped] = False
    bad_rows = np.flatnonzero(bad.any(axis=1))
    if bad_rows.size == 0:
        return None
    row = int(bad_rows[0])
    return row, int(np.flatnonzero(bad[row])[0])


@compiled
def first_non_finite_of_rigs(rows, start, stop, checked):
    """:func:`first_non_finite` of rows ``start:stop`` of every rig at once.

    Parameters
    ----------
    rows : ndarray (N, steps, N_COLUMNS)
        The rigs' recording rows (the float view of :func:`new_rows`).
    start, stop : int
        The rows to search.
    checked : ndarray (N, N_COLUMNS) of bool
        Whether each rig's column must be finite (False for its :func:`skipped_columns`).

    Returns
    -------
    ndarray (N, 2) of int
        Per rig, the (row counted from ``start``, column) of its first non-finite value in
        a checked column, or (-1, -1) if there is none.
    """
    found = np.full((rows.shape[0], 2), -1, dtype=np.int64)
    for rig in range(rows.shape[0]):
        for row in range(start, stop):
            for column in range(rows.shape[2]):
                if checked[rig, column] and not math.isfinite(rows[rig, row, column]):
                    found[rig, 0] = row - start
                    found[rig, 1] = column
                    break
            if found[rig, 0] >= 0:
                break
    return found


def as_columns(rows: np.ndarray) -> dict[str, np.ndarray]:
    """Rows as {column header: values}: each column contiguous, copied out of ``rows``
    in one transposing copy (one pass instead of a strided pass per column)."""
    return dict(zip(RIG_COLUMNS, rows.T.copy(), strict=True))


def record_rows(recorder: RunRecorder | None, block: np.ndarray) -> None:
    """Hand ``block`` to the recorder, if any and not empty."""
    if recorder is not None and block.shape[0]:
        recorder.append(block)


def stop_diverged(recorder: RunRecorder | None, rows: np.ndarray, flushed: int, good: int,
                  quantity: str, when: float, started: float, integrator: str,
                  rig: int | None = None) -> None:
    """Record rows ``flushed:good`` (the last good one is ``good - 1``) and raise
    :class:`RigDivergedError` naming ``quantity``, ``when`` [s] and, among several, the
    ``rig``."""
    record_rows(recorder, rows[flushed:good])
    result = RigResult(as_columns(rows[:good]), False, time.perf_counter() - started,
                       integrator)
    raise RigDivergedError(quantity, when, result, rig)

