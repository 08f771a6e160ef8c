"""The actuator bank: one owner of N actuators' parameters, state, supply and controllers.

:class:`ActuatorBank` holds, for N valve + cylinder actuators, the validated parameter
objects (:class:`~pneumaquad.params.ActuatorParameters`, one controller table each) and
everything the compiled code reads and writes: the packed parameter records, the chamber
state, the supply record(s), the outputs of the last step (:mod:`pneumaquad.core.layout`),
the PID gains and memory (:mod:`pneumaquad.core.control.pid`), the gain scales, the piston
references, the open-loop voltages and the valve commands. The arrays are the bank's own
(two banks never share memory) and never replaced, so bundles of them handed to compiled
code (:attr:`ActuatorBank.actuator_arrays`, :attr:`ActuatorBank.controller_arrays`) stay
valid for the bank's life.

Parameters change through named setters (:meth:`~ActuatorBank.set_supply_pressure`,
:meth:`~ActuatorBank.set_gains`, :meth:`~ActuatorBank.set_gain_scale`) that validate the
new value through the parameter model (the same range and cross-field checks as a
parameter file; a bad value raises :class:`~pneumaquad.params.ParameterError` naming the
key) and then repack the records from the updated objects, so the objects and the packed
data never disagree. Run-time quantities (references, voltages, state) are written
through :meth:`~ActuatorBank.set_references`, :meth:`~ActuatorBank.set_open_loop_voltages`
and :meth:`~ActuatorBank.reset`, or in place by the compiled step.

The robot (:mod:`pneumaquad.robot.joints`: all cylinders on one shared supply), the
network actuator side, the operator console and the rig (N independent rigs, one supply
each: :func:`pneumaquad.rig.model.rig_bank`) all hold their actuators in a bank. Units SI.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from pydantic import TypeAdapter, ValidationError

from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.control.pid import (
    PID_GAINS_DTYPE,
    controller_gains,
    new_pid_state,
    pid_update,
    scale_gains,
)
from pneumaquad.core.jit import compiled
from pneumaquad.core.layout import (
    ACTUATOR_PARAMETERS_DTYPE,
    ACTUATOR_STATE_DTYPE,
    RIG_PARAMETER_FIELDS,
    SUPPLY_TANK,
)
from pneumaquad.params import ActuatorParameters, ControllerParameters, ParameterError, Problem
from pneumaquad.params.loader import validated_update
from pneumaquad.params.robot_schema import GainScale

__all__ = [
    "ActuatorArrays",
    "ActuatorBank",
    "ControllerArrays",
    "scaled_pid_update",
]

#: Fields of the parameter records that come from the actuator objects (the rig fields
#: are packed by the rig and kept when the bank repacks).
_ACTUATOR_FIELDS = tuple(name for name in ACTUATOR_PARAMETERS_DTYPE.names
                         if name not in RIG_PARAMETER_FIELDS)
#: The PID fields of a controller table that :meth:`ActuatorBank.set_gains` changes.
GAIN_FIELDS = tuple(ControllerParameters.model_fields)

_GAIN_SCALE = TypeAdapter(GainScale)

Selection = int | slice | Sequence[int] | np.ndarray | None


class ActuatorArrays(NamedTuple):
    """The pneumatic kernel's record arrays (:mod:`pneumaquad.core.layout`)."""

    params: np.ndarray  # (N,) ACTUATOR_PARAMETERS_DTYPE
    state: np.ndarray  # (N,) ACTUATOR_STATE_DTYPE
    supply: np.ndarray  # (1,) SUPPLY_DTYPE shared, or (N,) one per actuator
    outputs: np.ndarray  # (N,) ACTUATOR_OUTPUT_DTYPE


class ControllerArrays(NamedTuple):
    """Per actuator: PID gains and memory, gain scale, piston reference, valve command."""

    gains: np.ndarray  # (N,) PID_GAINS_DTYPE
    gain_scale: np.ndarray  # (N,) factor on Kp, Ki, Kd [-]
    pid_state: np.ndarray  # (N,) PID_STATE_DTYPE
    references: np.ndarray  # (N,) piston position references [m]
    commands: np.ndarray  # (N,) valve voltages held over the step [V]


@compiled
def scaled_pid_update(controllers: ControllerArrays, index: int, measurement: float,
                      sample_time: float, scaled: np.void) -> float:
    """One PID sample of actuator ``index`` toward ``controllers.references[index]`` [m]
    from the piston position ``measurement`` [m], with Kp, Ki and Kd multiplied by
    ``controllers.gain_scale[index]``; ``scaled`` is a scratch PID_GAINS_DTYPE record.
    Returns the valve command [V] (not stored)."""
    scale_gains(controllers.gains[index], controllers.gain_scale[index], scaled)
    return pid_update(scaled, controllers.pid_state[index], controllers.references[index],
                      measurement, sample_time)


def _per_actuator(values: Any, count: int, name: str) -> np.ndarray:
    """``values`` broadcast to ``count`` floats; a shape mismatch names ``name``."""
    array = np.asarray(values, dtype=np.float64)
    try:
        return np.broadcast_to(array, (count,))
    except ValueError:
        raise ValueError(f"{name}: {array.shape[0] if array.ndim else 1} values for "
                         f"{count} actuators") from None


class ActuatorBank:
    """N actuators and their controllers: validated parameters and the packed arrays.

    Parameters
    ----------
    actuators : sequence of ActuatorParameters
        One per actuator, in order (the same object may drive several actuators).
    controllers : sequence of ControllerParameters
        The PID table of each actuator (a robot's ``JointControllerParameters`` adds
        ``gain_scale``, the starting value of :attr:`base_gain_scale`).
    supply_model : {"ideal", "tank"}, optional
        Override of the actuators' supply model.
    shared_supply : bool
        True: one supply record that every actuator draws from (built from the first
        actuator's supply table, as on the robot); False: one per actuator (independent
        rigs).

    Attributes
    ----------
    params, state, outputs : ndarray (N,)
        Kernel records (:mod:`pneumaquad.core.layout`).
    supply : ndarray (1,) or (N,)
        Supply record(s).
    gains, pid_state : ndarray (N,)
        PID records.
    base_gain_scale : ndarray (N,)
        Gain scale of the controller tables [-] (:meth:`set_gain_scale`).
    gain_scale : ndarray (N,)
        Scale in effect [-], written by gain schedules between steps.
    references : ndarray (N,)
        Piston position references of the PIDs [m].
    open_loop_voltage : ndarray (N,)
        Valve voltages of open-loop actuators [V].
    commands : ndarray (N,)
        Valve voltages held over the present step [V].
    """

    def __init__(
        self,
        actuators: Sequence[ActuatorParameters],
        controllers: Sequence[ControllerParameters],
        supply_model: str | None = None,
        shared_supply: bool = True,
    ) -> None:
        actuators, controllers = list(actuators), list(controllers)
        if not actuators or len(actuators) != len(controllers):
            raise ValueError(f"an actuator bank needs one controller per actuator, got "
                             f"{len(actuators)} actuators and {len(controllers)} controllers")
        if supply_model is not None:
            actuators = self._updated(actuators, range(len(actuators)),
                                      {"supply.model": [supply_model] * len(actuators)},
                                      "supply model override")
        self._actuators = actuators
        self._controllers = controllers
        n = len(actuators)
        self.params = pack_parameter_array(actuators)
        self.state = np.zeros(n, ACTUATOR_STATE_DTYPE)
        supplies = actuators[:1] if shared_supply else actuators
        self.supply = np.concatenate([supply_state(a) for a in supplies])
        self._initial_supply = self.supply.copy()
        self.outputs = new_outputs(n)
        self.gains = np.array([controller_gains(c, a.valve)
                               for c, a in zip(controllers, actuators, strict=True)],
                              dtype=PID_GAINS_DTYPE)
        self.pid_state = new_pid_state(n)
        self.base_gain_scale = np.array([getattr(c, "gain_scale", 1.0) for c in controllers])
        self.gain_scale = self.base_gain_scale.copy()
        self.references = np.zeros(n)
        self.open_loop_voltage = self.params["offset_voltage"].copy()
        self.commands = self.params["offset_voltage"].copy()
        #: The kernel's bundle of this bank's arrays (the same memory).
        self.actuator_arrays = ActuatorArrays(params=self.params, state=self.state,
                                              supply=self.supply, outputs=self.outputs)
        #: The controllers' bundle of this bank's arrays (the same memory).
        self.controller_arrays = ControllerArrays(
            gains=self.gains, gain_scale=self.gain_scale, pid_state=self.pid_state,
            references=self.references, commands=self.commands)

    # --- the validated parameter objects ---------------------------------------------
    @property
    def count(self) -> int:
        """Number of actuators."""
        return len(self._actuators)

    def __len__(self) -> int:
        return self.count

    @property
    def actuators(self) -> tuple[ActuatorParameters, ...]:
        """The validated actuator parameters, one per actuator (what :attr:`params`
        holds, packed)."""
        return tuple(self._actuators)

    @property
    def controllers(self) -> tuple[ControllerParameters, ...]:
        """The validated controller tables, one per actuator (what :attr:`gains` and
        :attr:`base_gain_scale` hold)."""
        return tuple(self._controllers)

    @property
    def shared_supply(self) -> bool:
        """Whether all actuators draw from one supply record."""
        return self.supply.shape[0] == 1

    def _indices(self, which: Selection) -> np.ndarray:
        """Actuator indices of a selection (all, an index, a slice, indices or a mask)."""
        everything = np.arange(self.count)
        return everything if which is None else np.atleast_1d(everything[which])

    @staticmethod
    def _updated(models: list[Any], indices: Any, changes: dict[str, Sequence[Any]],
                 source: str) -> list[Any]:
        """``models`` with each key of ``changes`` set to its values (one per index) at
        ``indices``; the changes of one model are validated together, once per distinct
        (object, values) pair."""
        models = list(models)
        done: dict[tuple[int, tuple[Any, ...]], Any] = {}
        for position, index in enumerate(indices):
            model = models[index]
            values = tuple(column[position] for column in changes.values())
            key = (id(model), values)
            if key not in done:
                done[key] = validated_update(model, dict(zip(changes, values, strict=True)),
                                             source=source)
            models[index] = done[key]
        return models

    def _repack(self, indices: np.ndarray) -> None:
        """Pack the actuator objects at ``indices`` into :attr:`params` (the rig fields,
        which come from a rig and not from the actuator, are kept)."""
        packed = pack_parameter_array([self._actuators[i] for i in indices])
        for name in _ACTUATOR_FIELDS:
            self.params[name][indices] = packed[name]

    # --- setters ---------------------------------------------------------------------
    def set_supply_pressure(self, pressure: float | np.ndarray,
                            which: Selection = None) -> None:
        """Regulated supply pressure [Pa, absolute] of the selected actuators (all by
        default): scalar or one value per selected actuator.

        Validated as ``supply.supply_pressure`` of each actuator's parameters (within
        (0, 100 MPa], above the exhaust pressure, at most a tank's initial pressure);
        nothing changes when a value is refused.

        Raises
        ------
        ParameterError
            Naming ``supply.supply_pressure``, the value and the expected range.
        """
        indices = self._indices(which)
        values = _per_actuator(pressure, indices.size, "supply pressure")
        self._actuators = self._updated(
            self._actuators, indices, {"supply.supply_pressure": [float(v) for v in values]},
            "supply pressure update")
        self._repack(indices)

    def set_gains(self, which: Selection = None, **fields: float) -> None:
        """Change PID fields of the selected controllers (all by default), e.g.
        ``set_gains(proportional_gain=80.0)`` [V/m]; keyword names are the fields of
        :class:`~pneumaquad.params.ControllerParameters` (``proportional_gain`` [V/m],
        ``integral_gain`` [V/(m s)], ``derivative_gain`` [V s/m],
        ``derivative_filter_time_constant`` [s], ``integral_limit`` [V]); a value is a
        scalar or one per selected controller. The PID memory is kept.

        Raises
        ------
        ParameterError
            A value outside the field's range, or an unknown field.
        """
        unknown = [name for name in fields if name not in GAIN_FIELDS]
        if unknown:
            raise ParameterError([Problem(name, fields[name], "is not a PID field; expected "
                                          f"one of {', '.join(GAIN_FIELDS)}")
                                  for name in unknown], source="gains update")
        indices = self._indices(which)
        changes = {name: [float(v) for v in _per_actuator(value, indices.size, name)]
                   for name, value in fields.items()}
        controllers = self._updated(self._controllers, indices, changes, "gains update")
        self._controllers = controllers
        for i in indices:
            self.gains[i] = controller_gains(controllers[i], self._actuators[i].valve)

    def set_gain_scale(self, scale: float | np.ndarray, which: Selection = None) -> None:
        """Gain scale [-] of the selected controllers (all by default): Kp, Ki and Kd are
        multiplied by it. Sets :attr:`base_gain_scale` and the scale in effect; validated
        as the controller table's ``gain_scale`` (within [0, 100]).

        Raises
        ------
        ParameterError
            Naming ``gain_scale`` and the value.
        """
        indices = self._indices(which)
        values = [float(v) for v in _per_actuator(scale, indices.size, "gain scale")]
        controllers = list(self._controllers)
        if all("gain_scale" in type(controllers[i]).model_fields for i in indices):
            controllers = self._updated(controllers, indices, {"gain_scale": values},
                                        "gain scale update")
        else:
            for value in values:
                try:
                    _GAIN_SCALE.validate_python(value)
                except ValidationError as error:
                    message = error.errors()[0]["msg"].removeprefix("Value error, ")
                    raise ParameterError([Problem("gain_scale", value, message)],
                                         source="gain_scale update") from None
        self._controllers = controllers
        self.base_gain_scale[indices] = values
        self.gain_scale[indices] = self.base_gain_scale[indices]

    def set_references(self, positions: float | np.ndarray, which: Selection = None) -> None:
        """Piston position references [m] of the selected PIDs (all by default)."""
        indices = self._indices(which)
        values = _per_actuator(positions, indices.size, "references")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"piston references must be finite, got {values}")
        self.references[indices] = values

    def set_open_loop_voltages(self, voltages: float | np.ndarray,
                               which: Selection = None) -> None:
        """Valve voltages [V] of the selected actuators (all by default) in open loop."""
        indices = self._indices(which)
        values = _per_actuator(voltages, indices.size, "voltages")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"valve voltages must be finite, got {values}")
        self.open_loop_voltage[indices] = values

    def reset(
        self,
        positions: float | np.ndarray,
        cap_pressure: float | np.ndarray | None = None,
        rod_pressure: float | np.ndarray | None = None,
    ) -> None:
        """Actuators at rest, controllers and supply back to their start.

        Parameters
        ----------
        positions : float or ndarray (N,)
            Piston extensions [m].
        cap_pressure : float or ndarray (N,), optional
            Absolute cap chamber pressures [Pa]; midway between each actuator's supply
            and exhaust pressure by default (a valve at rest near its centre).
        rod_pressure : float or ndarray (N,), optional
            Absolute rod chamber pressures [Pa]; the cap pressures by default.

        Notes
        -----
        The chamber masses follow from the ideal gas law at the supply temperature
        (:func:`~pneumaquad.core.actuator.initial_state`); PID memory and outputs are
        zeroed and the supply returns to its initial state (a full tank, nothing
        drawn). References, voltages and commands are kept.
        """
        n = self.count
        x = _per_actuator(positions, n, "positions")
        caps = None if cap_pressure is None else _per_actuator(cap_pressure, n, "cap pressure")
        rods = None if rod_pressure is None else _per_actuator(rod_pressure, n, "rod pressure")
        for i in range(n):
            p = self.params[i]
            cap = 0.5 * (p["supply_pressure"] + p["exhaust_pressure"]) if caps is None \
                else caps[i]
            rod = cap if rods is None else rods[i]
            initial_state(p, x[i], cap, rod, out=self.state[i])
        self.supply[:] = self._initial_supply
        self.pid_state[:] = 0.0
        self.outputs[:] = 0.0

    def restart_air_count(self) -> bool:
        """Start counting the air drawn again from 0 (per actuator and from the supply),
        the state otherwise as it is; not for a tank supply, whose pressure has dropped by
        the air counted (returns False then, True when restarted)."""
        if np.any(self.supply["model"] == SUPPLY_TANK):
            return False
        self.state["air_consumed"] = 0.0
        self.supply["drawn_mass"] = 0.0
        return True

    # --- readouts --------------------------------------------------------------------
    def chamber_pressures(self) -> np.ndarray:
        """(N, 2) cap and rod pressures [Pa], absolute."""
        return np.column_stack([self.state["cap_pressure"], self.state["rod_pressure"]])

    def forces(self) -> np.ndarray:
        """Net pneumatic force of each actuator [N] (eq 4.1.11 without friction)."""
        return self.outputs["pneumatic_force"].copy()

    def positions(self) -> np.ndarray:
        """Piston extensions [m] of the state."""
        return self.state["position"].copy()

    def air_consumed(self) -> float:
        """Air drawn from the supply (all supplies) since the start [kg]."""
        return float(self.supply["drawn_mass"].sum())

    def air_consumed_per_actuator(self) -> np.ndarray:
        """Air drawn by each actuator since the start [kg]."""
        return self.state["air_consumed"].copy()

    def supply_pressure(self, actuator: int = 0) -> float:
        """Pressure of the supply of ``actuator`` [Pa]: its tank pressure (tank supply) or
        its regulated supply pressure."""
        supply = self.supply[actuator if self.supply.shape[0] > 1 else 0]
        if supply["model"] == SUPPLY_TANK:
            return float(supply["tank_pressure"])
        return float(self.params[actuator]["supply_pressure"])

    def atmospheric_pressure(self) -> float:
        """Atmospheric pressure [Pa] of the first actuator's parameters."""
        return float(self.params[0]["atmospheric_pressure"])
