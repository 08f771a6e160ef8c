"""Analysis of recordings: zero-phase filtering, error and step metrics, step fits,
step-train segmentation and simulated-versus-measured comparison (thesis 4.2.1, 4.3), and
the fit-result type (`FitResult`) every fit of the package returns.

Pure functions over numpy arrays in SI units; recordings are dicts keyed
``"quantity [unit]"`` like those of the rig simulator.
"""

from .compare import (
    AlignedRecordings,
    SignalComparison,
    align_recordings,
    compare_recordings,
    comparison_rows,
    comparison_to_markdown,
)
from .filters import (
    amplitude_spectrum,
    apply_zero_phase,
    design_lowpass,
    lowpass_filter,
    sample_rate_of,
    velocity_from_position,
)
from .fits import (
    FIRST_ORDER,
    FIRST_PLUS_SECOND_ORDER,
    SECOND_ORDER,
    FitError,
    FitResult,
    evaluate_step_fit,
    fit_first_order,
    fit_first_plus_second_order,
    fit_second_order,
    fit_step,
)
from .metrics import (
    lag,
    max_abs_error,
    overshoot_percent,
    peak_time,
    rise_time,
    rmse,
    rmse_percent_of_range,
    settling_time,
    steady_state_error,
    step_metrics,
)
from .segmentation import StepSegment, find_steps, metrics_per_step

__all__ = [
    "FIRST_ORDER",
    "FIRST_PLUS_SECOND_ORDER",
    "SECOND_ORDER",
    "AlignedRecordings",
    "FitError",
    "FitResult",
    "SignalComparison",
    "StepSegment",
    "align_recordings",
    "amplitude_spectrum",
    "apply_zero_phase",
    "compare_recordings",
    "comparison_rows",
    "comparison_to_markdown",
    "design_lowpass",
    "evaluate_step_fit",
    "find_steps",
    "fit_first_order",
    "fit_first_plus_second_order",
    "fit_second_order",
    "fit_step",
    "lag",
    "lowpass_filter",
    "max_abs_error",
    "metrics_per_step",
    "overshoot_percent",
    "peak_time",
    "rise_time",
    "rmse",
    "rmse_percent_of_range",
    "sample_rate_of",
    "settling_time",
    "steady_state_error",
    "step_metrics",
    "velocity_from_position",
]
