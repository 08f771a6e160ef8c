"""Pure actuator physics: orifice flow, valve, chamber, friction, force, supply.

Every function here is a numba ``njit`` function on scalars in SI units, so the same code
serves the compiled multi-actuator kernel, the fixed-step rig integrator and the adaptive
``scipy.integrate.solve_ivp`` reference. They can also be called directly from Python.
"""

from pneumaquad.core.physics.chamber import (
    chamber_pressure_rate,
    chamber_temperature,
    chamber_volume_cap,
    chamber_volume_rod,
)
from pneumaquad.core.physics.force import gravity_force, piston_force
from pneumaquad.core.physics.friction import friction_force, stribeck_curve
from pneumaquad.core.physics.orifice import (
    iso6358_mass_flow,
    orifice_coefficients,
    orifice_flux,
    orifice_mass_flow,
)
from pneumaquad.core.physics.valve import input_pressure, polynomial_area, simple_valve_area

__all__ = [
    "chamber_pressure_rate",
    "chamber_temperature",
    "chamber_volume_cap",
    "chamber_volume_rod",
    "friction_force",
    "gravity_force",
    "input_pressure",
    "iso6358_mass_flow",
    "orifice_coefficients",
    "orifice_flux",
    "orifice_mass_flow",
    "piston_force",
    "polynomial_area",
    "simple_valve_area",
    "stribeck_curve",
]
