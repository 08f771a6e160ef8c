"""The study section of ``pneumaquad demo``: a short version of the shipped thesis
variability study (studies/thesis-variability-step.toml): 64 rig steps with the seal
friction drawn from the spread the thesis measured (4.2.2.4), run in this process, with
the study's own report beside the demo's."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pneumaquad.params.conversions import NEWTON_PER_LBF
from pneumaquad.reporting.display_units import DisplayUnits
from pneumaquad.studies import parse_study, read_results, run_study
from pneumaquad.studies.plots import distribution_png
from pneumaquad.studies.report import write_study_report

__all__ = ["STUDY_SECTIONS"]

#: The shipped study cut to 64 cases and a 2 s protocol (the step at 1 s).
SHORT_STUDY = """
[study]
name = "demo-thesis-variability-step"
sampling = "latin-hypercube"
cases = 64
seed = 2011
metrics = ["motion onset delay [s]", "rise time 10-90 % [s]", "stiction peak force [N]"]

[run]
kind = "rig-step"
voltage = "6 V"
step_time = "1 s"
duration = "2 s"

[vary."friction.static_force"]
distribution = "uniform"
low = "3.5 lbf"
high = "5.0 lbf"

[vary."friction.coulomb_force"]
distribution = "normal"
mean = "3 lbf"
std = "0.3 lbf"
low = "2 lbf"
high = "3.5 lbf"
"""


class Report(Protocol):
    units: DisplayUnits

    def add(self, title: str, text: str, figure: Path, figures: dict[str, Any]) -> None: ...


def _variability(folder: Path, report: Report) -> None:
    study = folder / "study-thesis-variability"
    spec = parse_study(SHORT_STUDY, "demo study")
    run = run_study(spec, study)
    table = read_results(study).to_pydict()
    write_study_report(study)
    peaks = np.array(table["stiction peak force [N]"], dtype=float)
    figure = study / "stiction-peak.png"
    figure.write_bytes(distribution_png("stiction peak force [N]", peaks))
    figures: dict[str, Any] = {"cases": run.total, "failed": run.failed}
    units = report.units
    for name in spec.metrics:
        spread = np.nanpercentile(np.array(table[name], dtype=float), [5, 50, 95])
        shown, values = units.key(name, spread)
        figures[f"{shown}: 5 %, median, 95 %"] = ", ".join(f"{v:.4g}" for v in values)
    low, high = (units.text(force * NEWTON_PER_LBF, "force", 3) for force in (3.5, 5.0))
    report.add(
        "Study: friction variability of the rig step",
        f"The thesis measured that the stiction of its cylinder varies between {low} and "
        f"{high} and that the Coulomb force scattered (4.2.2.4); this study draws both "
        "from that spread for 64 open-loop 6 V steps (Latin hypercube) and collects the "
        "break-away, rise time and stiction peak of each. The study's own report (with "
        "scatter plots and the sensitivity table) is study-thesis-variability/report.html; "
        "the full version is studies/thesis-variability-step.toml (docs/studies.md).",
        figure,
        figures,
    )


STUDY_SECTIONS = (_variability,)
