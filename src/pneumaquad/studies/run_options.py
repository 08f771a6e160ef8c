"""The base run of a study: its kind, parameter set, fixed overrides and run options.

A study's ``[run]`` table names one of :data:`RUN_KINDS` and that kind's options, written
like the command-line options of the same run (``voltage = "6.5 V"``, ``hold = "3 s"``).
Run options can be varied like parameters, under the key ``run.<option>``. This module
checks and converts the options to SI and writes the one command line that repeats a case.
"""

from __future__ import annotations

import math
import shlex
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pneumaquad.params.errors import ParameterError, Problem
from pneumaquad.params.units import parse_quantity

__all__ = ["RUN_KINDS", "RunOption", "RunSpec", "parse_run_options", "reproduce_command"]


@dataclass(frozen=True)
class RunOption:
    """One option of a run kind.

    Parameters
    ----------
    kind : str
        A quantity kind of :data:`pneumaquad.params.units.KINDS` (``"time"``), or
        ``"bool"``, ``"number"``, ``"seed"`` (an integer or ``"case"``: the case's own
        seed), or ``"choice"``.
    default : Any
        The option's value when the spec leaves it out; None: required (or, for walk
        settings, the library's default).
    flag : str
        The command-line option of the same run, for the repeating command (``""``: the
        positional argument).
    choices : tuple of str
        Allowed values of a ``"choice"`` option.
    number_scale : float or None
        For an option the command line takes as a plain number: SI value = number ×
        ``number_scale`` (``math.pi / 180`` for an angle given in degrees).
    """

    kind: str
    default: Any
    flag: str
    choices: tuple[str, ...] = ()
    number_scale: float | None = None


_ENVIRONMENTS = ("flat", "block", "ramp", "rough", "hill")
_ROBOT_COMMON = {
    "environment": RunOption("choice", "flat", "--environment", _ENVIRONMENTS),
    "seed": RunOption("seed", 0, "--seed"),
}

#: Run kinds, their default parameter set, and their options.
RUN_KINDS: dict[str, tuple[str, dict[str, RunOption]]] = {
    "rig-step": ("thesis-rig", {
        "voltage": RunOption("voltage", None, ""),
        "step_time": RunOption("time", "5 s", "--step-time"),
        "duration": RunOption("time", "10 s", "--duration"),
    }),
    "rig-sine": ("thesis-rig", {
        "mean": RunOption("length", "0.875 in", "--mean"),
        "amplitude": RunOption("length", "0.4 in", "--amplitude"),
        "frequency": RunOption("frequency", "0.5 Hz", "--frequency"),
        "duration": RunOption("time", "10 s", "--duration"),
    }),
    "robot-stand": ("crr-quadruped", {
        **_ROBOT_COMMON,
        "hold": RunOption("time", "3 s", "--hold"),
        "posture": RunOption("bool", True, "--posture"),
        "configuration": RunOption("choice", "quadruped", "--configuration",
                                   ("quadruped", "testbed")),
    }),
    "robot-walk": ("crr-quadruped", {
        **_ROBOT_COMMON,
        "distance": RunOption("length", None, "--distance", number_scale=1.0),
        "speed": RunOption("velocity", None, "--speed", number_scale=1.0),
        "heading": RunOption("angle", None, "--heading", number_scale=math.pi / 180.0),
        "period": RunOption("time", None, "--period", number_scale=1.0),
        "duty_factor": RunOption("number", None, "--duty-factor", number_scale=1.0),
    }),
}


@dataclass(frozen=True)
class RunSpec:
    """The base run of a study (the ``[run]`` table, checked).

    Parameters
    ----------
    kind : str
        One of :data:`RUN_KINDS`.
    params : str
        Parameter set name or TOML path.
    overrides : tuple of str
        Fixed ``--set`` items of every case.
    options : dict
        The run options as written in the spec (quantity strings), defaults filled in.
    """

    kind: str
    params: str
    overrides: tuple[str, ...]
    options: Mapping[str, Any] = field(default_factory=dict)

    @property
    def is_rig(self) -> bool:
        """Whether cases are rig runs (vectorised N-rig batches)."""
        return self.kind.startswith("rig-")


def _si(value: Any, option: RunOption, key: str, case_seed: int) -> Any:
    """One option's value in SI (quantities), or as it is (bool, number, choice)."""
    if option.kind == "bool":
        if not isinstance(value, bool):
            raise ParameterError([Problem(key, value, "should be true or false")])
        return value
    if option.kind == "number":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError([Problem(key, value, "should be a plain number")])
        return float(value)
    if option.kind == "seed":
        if value == "case":
            return case_seed
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ParameterError([Problem(key, value, 'should be an integer >= 0 or "case" '
                                          "(each case its own seed)")])
        return value
    if option.kind == "choice":
        if value not in option.choices:
            raise ParameterError([Problem(key, value,
                                          f"should be one of {', '.join(option.choices)}")])
        return value
    return parse_quantity(value, option.kind, key)


def parse_run_options(kind: str, options: Mapping[str, Any],
                      case_seed: int = 0) -> dict[str, Any]:
    """The options of a run of ``kind``, in SI [s, m, V, Hz, rad, m/s].

    Parameters
    ----------
    kind : str
        One of :data:`RUN_KINDS`.
    options : mapping
        Option name to its spec value (quantity string, bool, number, ``"case"``).
    case_seed : int
        The case's seed, for a ``seed = "case"`` option.

    Returns
    -------
    dict
        Every option of the kind; an option left out and without a default is None.

    Raises
    ------
    ParameterError
        Naming ``run.<option>``, the value and what was expected (also for an unknown
        option or a missing required one).
    """
    known = RUN_KINDS[kind][1]
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise ParameterError([Problem(f"run.{unknown[0]}", options[unknown[0]],
                                      f"is not an option of a {kind} run (options: "
                                      f"{', '.join(known)})")])
    values = {}
    for name, option in known.items():
        value = options.get(name, option.default)
        if value is None:
            if kind == "rig-step":
                raise ParameterError([Problem(f"run.{name}", None,
                                              f"is required by a {kind} run")])
            values[name] = None
            continue
        values[name] = _si(value, option, f"run.{name}", case_seed)
    return values


def reproduce_command(run: RunSpec, overrides: tuple[str, ...], options: Mapping[str, Any],
                      seed: int) -> str:
    """The one ``pneumaquad`` command line that runs a case alone.

    Parameters
    ----------
    run : RunSpec
    overrides : tuple of str
        The case's varied ``--set`` items (after the run's fixed ones).
    options : mapping
        The case's run options as written in the spec (varied ones included).
    seed : int
        The case's seed (for ``seed = "case"``).
    """
    known = RUN_KINDS[run.kind][1]
    words = {"rig-step": ["rig", "step"], "rig-sine": ["rig", "track", "sine"],
             "robot-stand": ["robot", "stand", "--no-video"],
             "robot-walk": ["robot", "walk", "--no-video"]}[run.kind]
    arguments = ["pneumaquad", *words]
    for name, option in known.items():
        value = options.get(name)
        if value is None:
            continue
        if option.kind == "seed" and value == "case":
            value = seed
        if option.number_scale is not None:
            si = _si(value, option, f"run.{name}", seed)
            value = f"{si / option.number_scale:.12g}"
        if option.kind == "bool":
            arguments.append(option.flag if value else f"--no-{option.flag[2:]}")
        elif option.flag:
            arguments += [option.flag, str(value)]
        else:
            arguments.append(str(value))
    arguments += ["--params", run.params]
    for item in (*run.overrides, *overrides):
        arguments += ["--set", item]
    return shlex.join(arguments)
