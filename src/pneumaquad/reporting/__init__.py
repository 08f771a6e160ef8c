"""Reports of run folders (issue #4): one self-contained HTML page plus PNGs.

``build_run_report(run)`` reads a rig or robot run folder and writes ``report.html`` with
the key parameters, the summary metrics, thesis-style time histories, the model curves of
the run's parameters (friction law, valve equivalent areas, input pressures) and, with
measured data, a measured-versus-simulated comparison, all in one display-unit system
(``DisplayUnits``: SI or the thesis's US units). ``measure_cost_table`` times the
components of the rig model like thesis Table 3; ``write_cost_table_report`` writes it.

The names below are loaded from their modules on first use (PEP 562), so importing
one module of the package does not import the others (and their SciPy or
Matplotlib).
"""

from pneumaquad import lazy_names

#: public name -> module of the package that defines it
_PUBLIC = {
    "area_curves": "curves",
    "AreaCurve": "curves",
    "build_run_report": "report",
    "compare_with_measured": "comparison",
    "CostRow": "cost_table",
    "CostTable": "cost_table",
    "DisplayUnits": "display_units",
    "escape": "html",
    "format_value": "html",
    "friction_curve": "curves",
    "HtmlPage": "html",
    "input_pressure_curves": "curves",
    "load_run_folder": "run_folder",
    "LoadedRun": "run_folder",
    "measure_cost_table": "cost_table",
    "MeasuredComparison": "comparison",
    "PressureCurve": "curves",
    "REPORT_NAME": "report",
    "ReportError": "run_folder",
    "write_cost_table_report": "cost_report",
    "write_run_report": "report",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
