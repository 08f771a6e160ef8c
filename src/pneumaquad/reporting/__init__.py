"""Reports of run folders (issue #4): one self-contained HTML page plus PNGs.

``build_run_report(run)`` reads a rig or robot run folder and writes ``report.html`` with
the key parameters, the summary metrics, thesis-style time histories, the model curves of
the run's parameters (friction law, valve equivalent areas, input pressures) and, with
measured data, a measured-versus-simulated comparison. ``measure_cost_table`` times the
components of the rig model like thesis Table 3; ``write_cost_table_report`` writes it.
"""

from .comparison import MeasuredComparison, compare_with_measured
from .cost_report import write_cost_table_report
from .cost_table import CostRow, CostTable, measure_cost_table
from .curves import (
    AreaCurve,
    PressureCurve,
    area_curves,
    friction_curve,
    input_pressure_curves,
)
from .html import HtmlPage, escape, format_value
from .report import REPORT_NAME, build_run_report, write_run_report
from .run_folder import LoadedRun, ReportError, load_run_folder

__all__ = [
    "REPORT_NAME",
    "AreaCurve",
    "CostRow",
    "CostTable",
    "HtmlPage",
    "LoadedRun",
    "MeasuredComparison",
    "PressureCurve",
    "ReportError",
    "area_curves",
    "build_run_report",
    "compare_with_measured",
    "escape",
    "format_value",
    "friction_curve",
    "input_pressure_curves",
    "load_run_folder",
    "measure_cost_table",
    "write_cost_table_report",
    "write_run_report",
]
