"""Export one actuator as an FMI 2.0 co-simulation FMU (``pneumaquad export fmu``,
docs/fmu.md).

The FMU is built with pythonfmu. Its ``resources`` folder holds a short Python module
whose class extends :class:`pneumaquad.interop.fmu_slave.ActuatorSlave`, the resolved
parameter set and the FMU's settings (:mod:`pneumaquad.interop.fmu_model`); its binaries
(Linux and Windows, 64 bit) are pythonfmu's, which run that module in the Python the
importing tool loads. That Python needs pneumaquad and pythonfmu installed
(``pip install "pneumaquad[fmu]"``): the FMU carries the data, the installed package the
code.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
from collections.abc import Iterable
from pathlib import Path

from pneumaquad.interop.fmu_model import PARAMETERS_FILE, SETTINGS_FILE, FmuSettings
from pneumaquad.params import (
    ActuatorParameters,
    ParameterError,
    Problem,
    RigSetup,
    resolved_parameters_toml,
)
from pneumaquad.params.loader import load_parameter_set

__all__ = [
    "DEFAULT_CONTROL_STEP",
    "DEFAULT_SUBSTEPS",
    "SLAVE_MODULE",
    "export_fmu",
    "export_settings",
    "model_identifier",
]

#: Kernel step of an FMU whose parameter set has no ``[simulation]`` table [s] (the
#: thesis's 1 ms).
DEFAULT_CONTROL_STEP = 1e-3
#: Heun substeps per kernel step without a ``[simulation]`` table (0.2 ms substeps: stable
#: for the thesis's cylinders, docs/physics.md).
DEFAULT_SUBSTEPS = 5
#: Name of the Python module inside the FMU.
SLAVE_MODULE = "pneumaquad_actuator"

_SLAVE_SOURCE = '''"""A pneumaquad actuator as an FMI 2.0 co-simulation slave.

Written by `pneumaquad export fmu`. The actuator's parameters are in parameters.toml and the
FMU's settings in fmu_settings.json beside this file; the code is the installed pneumaquad's
(pneumaquad.interop.fmu_slave), so the Python that runs this FMU needs pneumaquad and
pythonfmu: pip install "pneumaquad[fmu]".
"""

try:
    from pneumaquad.interop.fmu_runtime import hold_namespace
    from pneumaquad.interop.fmu_slave import ActuatorSlave
except ImportError as error:
    raise ImportError(
        "this FMU runs the actuator code of pneumaquad, which the Python that loads it cannot "
        f"import ({error}); install it there: pip install \\"pneumaquad[fmu]\\""
    ) from error

# pythonfmu runs this code again at each instantiation and then drops a reference to this
# namespace it does not hold; this call holds one more each time (see hold_namespace).
hold_namespace(globals())


class PneumaquadActuator(ActuatorSlave):
    """The actuator of the parameter set in this FMU's resources."""
'''


def model_identifier(parameter_set: str | os.PathLike[str]) -> str:
    """The FMU's model name and identifier for a parameter set, from its name or its
    file's name: ``"crr-gamma"`` -> ``"pneumaquad_crr_gamma"``, ``"runs/my-gamma.toml"``
    -> ``"pneumaquad_my_gamma"`` (a C identifier, as FMI requires)."""
    name = Path(parameter_set).stem
    return "pneumaquad_" + re.sub(r"\W", "_", name, flags=re.ASCII)


def export_settings(
    parameter_set: str | os.PathLike[str], overrides: Iterable[str] = ()
) -> tuple[ActuatorParameters, FmuSettings]:
    """The actuator and the FMU settings of a parameter set.

    An actuator file (``crr-gamma``) gives the actuator; the FMU then starts mid-stroke
    with both chambers midway between supply and exhaust pressure, and steps 1 ms with 5
    substeps. A rig file (``thesis-rig``) gives its actuator, its initial position and
    pressures and its ``[simulation]`` step and substeps.

    Parameters
    ----------
    parameter_set : str or path-like
        A shipped set name or a TOML path.
    overrides : iterable of str
        ``section.key=value`` items, as ``--set``.

    Returns
    -------
    (ActuatorParameters, FmuSettings)

    Raises
    ------
    ParameterError
        An unknown set, a bad value, or a robot file (its actuators are separate sets).
    """
    from pneumaquad import __version__

    loaded = load_parameter_set(parameter_set, overrides)
    if isinstance(loaded, RigSetup):
        actuator = loaded.actuator
        position = loaded.rig.initial_position
        cap, rod = loaded.rig.initial_cap_pressure, loaded.rig.initial_rod_pressure
        control_step, substeps = loaded.simulation.control_step, loaded.simulation.substeps
    elif isinstance(loaded, ActuatorParameters):
        actuator = loaded
        position = 0.5 * actuator.cylinder.stroke
        cap = rod = 0.5 * (actuator.supply.supply_pressure + actuator.supply.exhaust_pressure)
        control_step, substeps = DEFAULT_CONTROL_STEP, DEFAULT_SUBSTEPS
    else:
        raise ParameterError([Problem("<set>", str(parameter_set),
                                      "is a robot file; an FMU holds one actuator: export one "
                                      "of the actuator sets it names (crr-alpha, crr-beta, "
                                      "crr-gamma) or a rig file")])
    settings = FmuSettings(
        model_name=model_identifier(parameter_set),
        parameter_set=str(parameter_set),
        pneumaquad_version=__version__,
        control_step=control_step,
        substeps=substeps,
        initial_position=position,
        initial_cap_pressure=cap,
        initial_rod_pressure=rod,
    )
    return actuator, settings


def export_fmu(parameter_set: str | os.PathLike[str], output: str | os.PathLike[str],
               overrides: Iterable[str] = ()) -> Path:
    """Write the FMU of one actuator.

    Parameters
    ----------
    parameter_set : str or path-like
        A shipped set name (``"crr-gamma"``) or a TOML path: an actuator or rig file
        (:func:`export_settings`).
    output : str or path-like
        The ``.fmu`` file to write (replaced if it exists; its folder is created).
    overrides : iterable of str
        ``section.key=value`` items changing the set before export.

    Returns
    -------
    pathlib.Path
        The FMU written.

    Raises
    ------
    ParameterError
        A bad parameter set or an output name that does not end in ``.fmu``.
    ModuleNotFoundError
        pythonfmu is not installed (``pip install "pneumaquad[fmu]"``).
    """
    from pythonfmu import FmuBuilder

    target = Path(output)
    if target.suffix != ".fmu" or target.is_dir():
        raise ParameterError([Problem("output", str(target), "should be a file name ending "
                                      "in .fmu")])
    actuator, settings = export_settings(parameter_set, overrides)
    target.parent.mkdir(parents=True, exist_ok=True)
    loaded_before = SLAVE_MODULE in sys.modules
    with tempfile.TemporaryDirectory(prefix="pneumaquad-fmu-") as folder:
        script = Path(folder) / f"{SLAVE_MODULE}.py"
        script.write_text(_SLAVE_SOURCE, encoding="utf-8")
        parameters = Path(folder) / PARAMETERS_FILE
        parameters.write_text(resolved_parameters_toml(actuator), encoding="utf-8")
        settings_file = Path(folder) / SETTINGS_FILE
        settings.write(settings_file)
        try:
            built = FmuBuilder.build_FMU(script, dest=target,
                                         project_files=[parameters, settings_file])
        finally:  # the builder imports the module from the folder and leaves it on the path
            while folder in sys.path:
                sys.path.remove(folder)
            if not loaded_before:
                sys.modules.pop(SLAVE_MODULE, None)
    return Path(built)
