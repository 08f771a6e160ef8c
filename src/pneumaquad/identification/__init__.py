"""Parameter identification from rig recordings (thesis 4.2.2-4.2.3, App. B.2).

Friction from open-loop steps (stiction peaks, Coulomb-viscous and Stribeck-tanh fits),
the underlapped valve's input-pressure curves from fixed-piston tests, equivalent orifice
areas fitted around the rig simulator and their polynomials, the PID controller from
closed-loop recordings, and parameter files written from the results. Pure functions
over recordings (dicts of SI arrays keyed ``"quantity [unit]"``, simulated or from
`pneumaquad.io.measured`).

Every fit returns the package's one result type, `pneumaquad.analysis.fits.FitResult`
(re-exported here with `check_standard_errors`).
"""

from pneumaquad.analysis.fits import FitResult, check_standard_errors

from .friction import (
    STRIBECK_TANH_PARAMETERS,
    FrictionPoints,
    StictionEstimate,
    fit_coulomb_viscous,
    fit_stribeck_tanh,
    kinetic_friction_points,
    stiction_from_step,
    stribeck_tanh_curve,
    summarize_stiction,
)
from .preprocess import (
    FilterSettings,
    IdentificationError,
    PreparedSignals,
    prepare_signals,
    select_step,
)
from .report import updates_from_fit, write_parameter_file
from .valve import (
    AreaPolynomials,
    EquivalentAreaFit,
    InputPressureCurves,
    SteadyStatePoints,
    area_polynomial_updates,
    areas_table,
    equivalent_area_for_step,
    fit_area_polynomials,
    fit_input_pressure_curve,
    input_pressure_curves,
    start_temperatures_from_hold,
    steady_state_points,
)

__all__ = [
    "METHODS",
    "STRIBECK_TANH_PARAMETERS",
    "AreaPolynomials",
    "ClosedLoopRecording",
    "ControllerFit",
    "EquivalentAreaFit",
    "FilterSettings",
    "FitResult",
    "FrictionPoints",
    "IdentificationError",
    "InputPressureCurves",
    "PreparedSignals",
    "SteadyStatePoints",
    "StictionEstimate",
    "area_polynomial_updates",
    "areas_table",
    "check_standard_errors",
    "closed_loop_recording",
    "equivalent_area_for_step",
    "fit_area_polynomials",
    "fit_controller",
    "fit_coulomb_viscous",
    "fit_input_pressure_curve",
    "fit_stribeck_tanh",
    "input_pressure_curves",
    "kinetic_friction_points",
    "prepare_signals",
    "select_step",
    "start_temperatures_from_hold",
    "steady_state_points",
    "stiction_from_step",
    "stribeck_tanh_curve",
    "summarize_stiction",
    "updates_from_fit",
    "write_parameter_file",
]

#: The controller fit's names, imported on first use: it loads scipy.signal and the rig's
#: compiled loop, which the command line's start (and ``--help``) does not need.
_LAZY = {
    "METHODS": "controller",
    "fit_controller": "controller",
    "ClosedLoopRecording": "controller_data",
    "ControllerFit": "controller_data",
    "closed_loop_recording": "controller_data",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

