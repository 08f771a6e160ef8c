"""Parameter sets: TOML files with units, validated into frozen SI pydantic models.

See docs/parameters.md for the file layout. Typical use::

    from pneumaquad.params import load_rig
    setup = load_rig("thesis-rig", overrides=["supply.supply_pressure=30 psig"])
    setup.actuator.supply.supply_pressure  # Pa, absolute
"""

from .errors import MISSING, ParameterError, Problem
from .loader import (
    DATA_DIR,
    apply_overrides,
    list_parameter_sets,
    load_actuator,
    load_rig,
    load_robot,
    resolved_parameters_toml,
)
from .robot_schema import JOINT_NAMES, LEG_NAMES, RobotParameters
from .schema import (
    ActuatorParameters,
    ControllerParameters,
    CylinderParameters,
    FrictionParameters,
    GasParameters,
    Meta,
    RigControllerParameters,
    RigParameters,
    RigSetup,
    SimpleValveParameters,
    SimulationParameters,
    SupplyParameters,
    ThermodynamicsParameters,
    ValveParameters,
    ValvePortParameters,
    orientation_to_angle,
)
from .units import parse_quantity, ureg

__all__ = [
    "DATA_DIR",
    "JOINT_NAMES",
    "LEG_NAMES",
    "MISSING",
    "ActuatorParameters",
    "ControllerParameters",
    "CylinderParameters",
    "FrictionParameters",
    "GasParameters",
    "Meta",
    "ParameterError",
    "Problem",
    "RigControllerParameters",
    "RigParameters",
    "RigSetup",
    "RobotParameters",
    "SimpleValveParameters",
    "SimulationParameters",
    "SupplyParameters",
    "ThermodynamicsParameters",
    "ValveParameters",
    "ValvePortParameters",
    "apply_overrides",
    "list_parameter_sets",
    "load_actuator",
    "load_rig",
    "load_robot",
    "orientation_to_angle",
    "parse_quantity",
    "resolved_parameters_toml",
    "ureg",
]
