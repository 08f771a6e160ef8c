"""Analysis of recordings: zero-phase filtering, error and step metrics, step fits,
step-train segmentation and simulated-versus-measured comparison (thesis 4.2.1, 4.3), and
the fit-result type (`FitResult`) every fit of the package returns.

Pure functions over numpy arrays in SI units; recordings are dicts keyed
``"quantity [unit]"`` like those of the rig simulator.

The names below are loaded from their modules on first use (PEP 562), so importing
one module of the package does not import the others (and their SciPy or
Matplotlib).
"""

from pneumaquad import lazy_names

#: public name -> module of the package that defines it
_PUBLIC = {
    "align_recordings": "compare",
    "AlignedRecordings": "compare",
    "amplitude_spectrum": "filters",
    "apply_zero_phase": "filters",
    "compare_recordings": "compare",
    "comparison_rows": "compare",
    "comparison_to_markdown": "compare",
    "design_lowpass": "filters",
    "evaluate_step_fit": "fits",
    "find_steps": "segmentation",
    "FIRST_ORDER": "fits",
    "FIRST_PLUS_SECOND_ORDER": "fits",
    "fit_first_order": "fits",
    "fit_first_plus_second_order": "fits",
    "fit_second_order": "fits",
    "fit_step": "fits",
    "FitError": "fits",
    "FitResult": "fits",
    "lag": "metrics",
    "lowpass_filter": "filters",
    "max_abs_error": "metrics",
    "metrics_per_step": "segmentation",
    "overshoot_percent": "metrics",
    "peak_time": "metrics",
    "rise_time": "metrics",
    "rmse": "metrics",
    "rmse_percent_of_range": "metrics",
    "sample_rate_of": "filters",
    "SECOND_ORDER": "fits",
    "settling_time": "metrics",
    "SignalComparison": "compare",
    "steady_state_error": "metrics",
    "step_metrics": "metrics",
    "StepSegment": "segmentation",
    "velocity_from_position": "filters",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
