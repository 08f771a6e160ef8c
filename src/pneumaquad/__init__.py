"""pneumaquad: simulator for pneumatically actuated legged robots.

The few names most work starts from are available here; each is loaded on first use, so
``import pneumaquad`` stays quick and does not load MuJoCo or compile anything:

- parameters: :func:`load_rig`, :func:`load_robot`, :func:`load_actuator`,
  :func:`list_parameter_sets` (TOML with units, validated, SI inside);
- the 1-DoF rig: :func:`simulate_rig`, :func:`simulate_rigs` (N rigs in one compiled
  loop, e.g. a parameter sweep) and the reference signals in :mod:`signals`;
- the robot: :func:`build_robot` (MuJoCo model on the 12 cylinders) and
  :class:`RobotSimulation` (the coupled actuator + MuJoCo step);
- results: :func:`read_run` (recording with units, parameters and summary of a run
  folder; also under its earlier name ``read_run_folder``) and :func:`read_recording` (a
  recording file or a run folder's recording).

Everything else lives in the layers listed in the README's "Layout".
"""

import sys
from collections.abc import Callable
from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("pneumaquad")  # one source: pyproject.toml
except PackageNotFoundError:  # pragma: no cover - run from a source tree, not installed
    __version__ = "0+unknown"

#: public name -> module that defines it
_PUBLIC = {
    "load_rig": "pneumaquad.params.loader",
    "load_robot": "pneumaquad.params.loader",
    "load_actuator": "pneumaquad.params.loader",
    "list_parameter_sets": "pneumaquad.params.loader",
    "simulate_rig": "pneumaquad.rig.simulate",
    "simulate_rigs": "pneumaquad.rig.simulate",
    "signals": "pneumaquad.rig.signals",
    "build_robot": "pneumaquad.robot.builder",
    "RobotSimulation": "pneumaquad.robot.simulation",
    "read_run": "pneumaquad.io.run_folder",
    "read_run_folder": "pneumaquad.io.run_folder",
    "read_recording": "pneumaquad.io.run_folder",
}

__all__ = ["__version__", *_PUBLIC]


def lazy_names(package: str, public: dict[str, str]
               ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of a package whose public names load on first
    use (PEP 562).

    ``public`` maps each name to the module that defines it, absolute or relative to
    ``package`` (``"metrics"``); a name that is its module's last component is the module
    itself. A loaded name is kept in the package's namespace.
    """

    def load(name: str) -> Any:
        module_name = public.get(name)
        if module_name is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        absolute = module_name if "." in module_name else f"{package}.{module_name}"
        module = import_module(absolute)
        value = module if absolute.rsplit(".", 1)[1] == name else getattr(module, name)
        setattr(sys.modules[package], name, value)
        return value

    def names() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(public))

    return load, names


__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
