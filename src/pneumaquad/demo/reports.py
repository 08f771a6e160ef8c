"""Demo sections that exercise the analysis and report tools on demo runs.

* The closed-loop step train of the rig is compared with a stand-in for lab data: the same
  experiment simulated with LuGre friction instead of Stribeck-tanh, 20 µm position noise,
  0.3 kPa pressure noise and a 20 ms delay, written as a lab-style CSV (ms, in, psig, with
  the valve command and the reference position, the input of ``pneumaquad fit
  controller``) with a column mapping, and imported back through
  :mod:`pneumaquad.io.measured`.
* Stand-in lab data for identification (`write_identification_lab_data`): a fixed-piston
  sweep and open-loop steps of ``thesis-rig`` in the same lab format with a command column,
  the input of the README's ``pneumaquad fit`` example.
* Each of those runs, and the quadruped stand-up, gets its own ``pneumaquad report``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pneumaquad.io.run_folder import read_json
from pneumaquad.params import load_rig
from pneumaquad.params.conversions import METRE_PER_INCH as INCH
from pneumaquad.params.conversions import PASCAL_PER_PSI as PSI
from pneumaquad.reporting import build_run_report
from pneumaquad.reporting.display_units import DisplayUnits
from pneumaquad.reporting.sections import COMPARISON_NAME
from pneumaquad.rig import signals
from pneumaquad.rig.simulate import simulate_rig

__all__ = [
    "LAB_SPACER_VOLTAGES",
    "LAB_STEP_VOLTAGES",
    "REPORT_SECTIONS",
    "write_identification_lab_data",
    "write_lab_style_csv",
]

_STEP_LEVELS = [0.4 * INCH, 1.4 * INCH, 0.6 * INCH, 1.2 * INCH, 0.875 * INCH]
#: Held commands of the stand-in spacer sweep [V]: both ports' transitions (thesis-rig
#: centred voltages -1.25...+0.75 and -0.75...+1.25) hold several each.
LAB_SPACER_VOLTAGES = (3.5, 4.0, 4.4, 4.75, 5.0, 5.25, 5.5, 5.75, 6.0, 6.5, 7.0)
#: Commands of the stand-in open-loop steps [V]: valve offset 5.25 V plus the centred
#: voltages -3 ... +3 V, five or more on each side for the area polynomials (App. B.2).
LAB_STEP_VOLTAGES = (2.25, 3.25, 4.0, 4.5, 4.9, 5.25, 5.6, 6.0, 6.5, 7.25, 8.25)


class Report(Protocol):
    units: DisplayUnits

    def add(self, title: str, text: str, figure: Path, figures: dict[str, Any]) -> None: ...


def write_lab_style_csv(
    recording: dict[str, np.ndarray],
    folder: Path,
    delay: float,
    seed: int = 1,
    position_noise: float = 20e-6,
    pressure_noise: float = 300.0,
    name: str = "lab-step-train",
    atmosphere: float = 101325.0,
    with_command: bool = False,
    mapping_name: str | None = None,
    with_reference: bool = False,
) -> tuple[Path, Path]:
    """Write a rig recording as a lab CSV (ms, in, psig) and its column-mapping TOML.

    Parameters
    ----------
    recording : dict
        Rig recording (SI).
    folder : Path
        Where ``<name>.csv`` and ``<name>-mapping.toml`` go.
    delay : float
        The "measured" signals lag the recording by this much [s].
    seed : int
        Seed of the noise.
    position_noise, pressure_noise : float
        Standard deviations of added white noise [m], [Pa].
    name : str
        File stem.
    atmosphere : float
        Atmospheric pressure for the gauge columns [Pa].
    with_command : bool
        Also write the valve command (column ``u_V``, volts, no noise) and map it.
    mapping_name : str, optional
        Stem of the mapping file; ``<name>-mapping`` by default. Files of the same
        columns can share one.
    with_reference : bool
        Also write the reference position of a closed-loop run (column ``r_in``, inches,
        no noise) and map it.
    """
    generator = np.random.default_rng(seed)
    time = recording["time [s]"] + delay
    position = recording["position [m]"] + generator.normal(0.0, position_noise, time.size)
    cap = recording["cap pressure [Pa]"] + generator.normal(0.0, pressure_noise, time.size)
    rod = recording["rod pressure [Pa]"] + generator.normal(0.0, pressure_noise, time.size)
    columns = [time * 1e3, position / INCH, (cap - atmosphere) / PSI, (rod - atmosphere) / PSI]
    header = "t_ms,x_in,p_cap_psig,p_rod_psig"
    if with_command:
        columns.append(recording["command [V]"])
        header += ",u_V"
    if with_reference:
        columns.append(recording["reference position [m]"] / INCH)
        header += ",r_in"
    folder.mkdir(parents=True, exist_ok=True)
    csv = folder / f"{name}.csv"
    np.savetxt(csv, np.column_stack(columns), delimiter=",", header=header, comments="",
               fmt="%.15g")
    mapping = folder / f"{mapping_name or name + '-mapping'}.toml"
    described = csv.name if mapping_name is None else f"the lab CSVs ({header})"
    mapping.write_text(
        f"# Column mapping of {described} for pneumaquad.io.measured\n"
        f"atmospheric_pressure = {atmosphere!r}\n[columns]\n"
        'time = { source = "t_ms", unit = "ms" }\n'
        'position = { source = "x_in", unit = "in" }\n'
        'cap_pressure = { source = "p_cap_psig", unit = "psig" }\n'
        'rod_pressure = { source = "p_rod_psig", unit = "psig" }\n'
        + ('command = { source = "u_V", unit = "V" }\n' if with_command else "")
        + ('reference_position = { source = "r_in", unit = "in" }\n' if with_reference
           else ""),
        encoding="utf-8",
    )
    return csv, mapping


def write_identification_lab_data(
    folder: Path,
    *,
    spacer_voltages: Sequence[float] = LAB_SPACER_VOLTAGES,
    spacer_hold: float = 5.0,
    step_voltages: Sequence[float] = LAB_STEP_VOLTAGES,
    step_time: float = 2.0,
    step_duration: float = 3.5,
    delay: float = 0.02,
    seed: int = 2,
) -> dict[str, list[Path]]:
    """Stand-in lab data for ``pneumaquad fit``: a spacer sweep and open-loop steps.

    Simulated with ``thesis-rig`` (its cutoffs, area polynomials and Stribeck-tanh
    friction are what a fit should give back) and written like `write_lab_style_csv`
    (ms, in, psig, 20 µm and 0.3 kPa noise, ``delay``) with the command in volts:
    ``spacer-sweep.csv`` (piston held, each of ``spacer_voltages`` for ``spacer_hold``),
    ``open-loop-step-<V>.csv`` (thesis protocol, 4.2.3: the opposite saturation until
    ``step_time``, then the step) and one mapping, ``identification-mapping.toml``.

    Parameters
    ----------
    folder : Path
        Where the files go.
    spacer_voltages : sequence of float
        Held commands of the sweep [V].
    spacer_hold : float
        Time at each held command [s].
    step_voltages : sequence of float
        Step commands [V], one file each.
    step_time, step_duration : float
        Time of each step and length of each step file [s].
    delay : float
        Time offset of the "measured" files [s].
    seed : int
        Seed of the noise (each file its own stream).

    Returns
    -------
    dict
        ``{"spacer": [csv], "steps": [csv, ...], "mapping": [toml]}``.
    """
    mapping_name = "identification-mapping"
    fixed = load_rig("thesis-rig", ["rig.spacer=true"])
    control_step = fixed.simulation.control_step
    sweep = signals.step_train(list(spacer_voltages), spacer_hold, control_step)
    spacer_csv, mapping = write_lab_style_csv(
        simulate_rig(fixed, sweep, closed_loop=False).recording,
        folder,
        delay,
        seed=seed,
        name="spacer-sweep",
        with_command=True,
        mapping_name=mapping_name,
    )
    setup = load_rig("thesis-rig")
    valve = setup.actuator.valve
    step_files = []
    for index, voltage in enumerate(step_voltages):
        command = signals.thesis_step_command(
            voltage,
            valve.offset_voltage,
            valve.min_voltage,
            valve.max_voltage,
            control_step,
            step_time,
            step_duration,
        )
        csv, _ = write_lab_style_csv(
            simulate_rig(setup, command, closed_loop=False).recording,
            folder,
            delay,
            seed=seed + 1 + index,
            name=f"open-loop-step-{voltage:.2f}V".replace(".", "_"),
            with_command=True,
            mapping_name=mapping_name,
        )
        step_files.append(csv)
    return {"spacer": [spacer_csv], "steps": step_files, "mapping": [mapping]}


def _measured_comparison(folder: Path, report: Report) -> None:
    setup = load_rig("thesis-rig", ['friction.model="lugre"'])
    reference = signals.step_train(_STEP_LEVELS, 2.0, setup.simulation.control_step)
    lab = simulate_rig(setup, reference, closed_loop=True).recording
    csv, mapping = write_lab_style_csv(lab, folder / "lab-data", delay=0.02, with_command=True,
                                       with_reference=True)
    page = build_run_report(folder / "step-train", measured=csv, mapping=mapping,
                            units=report.units)
    figures: dict[str, Any] = {"report": str(page.relative_to(folder))}
    comparison = read_json(page.parent / COMPARISON_NAME)
    for row in comparison["signals"]:  # SI: positions in m, pressures in Pa
        name, _, unit = row["signal"].rpartition(" [")
        unit, scale = ("mm", 1e3) if unit == "m]" else (unit.rstrip("]"), 1.0)
        figures[f"{name} RMSE [{unit}]"] = row["rmse"] * scale
        figures[f"{name} RMSE [% of range]"] = row["rmse_percent"]
        figures[f"{name} lag [s]"] = row["lag"]
    report.add(
        "Simulation against (stand-in) lab data",
        "The closed-loop step train compared with 'measured' data: the same experiment "
        "simulated with LuGre friction, 20 µm and 0.3 kPa noise and a 20 ms delay, written "
        "as a lab CSV in ms, inches and psig with a column mapping (lab-data/), imported and "
        "aligned by `pneumaquad report step-train --measured ... --mapping ...`. The "
        "lag comes back as −0.02 s (the simulation leads).",
        page.parent / "measured-vs-simulated.png",
        figures,
    )


def _identification_data(folder: Path, report: Report) -> None:
    """Write the stand-in identification data (no report section: the README fits it)."""
    del report
    write_identification_lab_data(folder / "lab-data")


def _robot_report(folder: Path, report: Report) -> None:
    page = build_run_report(folder / "robot-stand", units=report.units)
    report.add(
        "Report of a robot run",
        "`pneumaquad report robot-stand`: parameters, metrics, joint and body plots, "
        "the actuators' friction, valve-area and input-pressure curves; below, its "
        "thorax height, attitude, foot forces and air consumed.",
        page.parent / "body.png",
        {"report": str(page.relative_to(folder))},
    )


REPORT_SECTIONS = (_measured_comparison, _identification_data, _robot_report)
