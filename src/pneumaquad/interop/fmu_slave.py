"""The actuator as an FMI 2.0 co-simulation slave (pythonfmu's ``Fmi2Slave``).

:class:`ActuatorSlave` runs one valve + cylinder actuator with the project's own compiled
kernel (:func:`pneumaquad.core.kernel.step_actuators`, the one the robot uses): the load
side gives the piston's position and velocity and the valve voltage, the FMU returns the
force, the chamber states, the flows and the air used. Its variables are those of
:mod:`pneumaquad.interop.fmu_model`; the start values of its parameters come from the
parameter set and settings in the FMU's ``resources`` folder. An exported FMU
(:func:`pneumaquad.interop.fmu_export.export_fmu`) holds a subclass of it that adds nothing,
so the code that runs is the installed pneumaquad's.

Life cycle (FMI 2.0 co-simulation):

* instantiation reads the resources and prepares the actuator from the start values;
* parameters are ``fixed``: they may be set until ``exitInitializationMode``, which
  validates them all (ranges and cross-field checks of the parameter files; a bad value
  fails the call with a message naming the key) and puts the pistons at rest at the
  ``piston_position`` input with the ``initial.*`` chamber pressures;
* ``doStep(t, H)`` splits H into ``ceil(H / simulation.control_step)`` equal kernel steps
  and advances them with the inputs held: the valve voltage and the piston velocity
  constant, the position moving on from the input at that velocity. The outputs are the
  state at the end of the step (flows: their mean over it);
* ``reset`` (pythonfmu builds the object again) returns to the state after instantiation.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import TypeAdapter, ValidationError
from pythonfmu import (
    DefaultExperiment,
    Fmi2Causality,
    Fmi2Slave,
    Fmi2Variability,
    Integer,
    Real,
    String,
)
from pythonfmu.enums import Fmi2Status

from pneumaquad.core.actuator import (
    initial_state,
    new_outputs,
    pack_parameter_array,
    supply_state,
)
from pneumaquad.core.kernel import step_actuators
from pneumaquad.core.layout import ACTUATOR_STATE_DTYPE
from pneumaquad.core.pneumatics import friction_of, state_outputs, supply_pressure_now
from pneumaquad.interop.fmu_model import (
    INPUTS,
    OUTPUTS,
    PARAMETERS_FILE,
    SETTING_FIELDS,
    SETTING_VARIABLES,
    SETTINGS_FILE,
    FmuSettings,
    FmuVariable,
    complete_model_description,
    parameter_changes,
    parameter_variables,
)
from pneumaquad.interop.fmu_runtime import guard_entry_points, release_at_exit
from pneumaquad.params import ActuatorParameters, ParameterError, Problem, load_actuator
from pneumaquad.params.fields import AbsolutePressure, ControlStep, StepCount
from pneumaquad.params.loader import validated_update

__all__ = ["ActuatorSlave", "FixedParameterError"]

#: Relative slack when a communication step is divided into kernel steps: a step of
#: 5.000000000000001 kernel steps (rounding of 0.005 / 0.001) is five of them.
STEP_SLACK = 1e-9

_SETTING_TYPES = {
    "initial.cap_pressure": TypeAdapter(AbsolutePressure),
    "initial.rod_pressure": TypeAdapter(AbsolutePressure),
    "simulation.control_step": TypeAdapter(ControlStep),
    "simulation.substeps": TypeAdapter(StepCount),
}

_VARIABLE_TYPES = {"real": Real, "integer": Integer, "string": String}

#: Outputs read from the state record, from the kernel's output record, and the mean flows.
_STATE_OUTPUTS = ("cap_pressure", "rod_pressure", "air_consumed")
_KERNEL_OUTPUTS = ("pneumatic_force", "friction_force", "cap_temperature", "rod_temperature")
_MEAN_FLOWS = ("cap_mass_flow", "rod_mass_flow", "supply_mass_flow")


class FixedParameterError(RuntimeError):
    """A parameter was set after initialisation (FMI variability ``fixed``)."""


class ActuatorSlave(Fmi2Slave):
    """One pneumatic actuator as an FMI 2.0 co-simulation slave.

    Parameters
    ----------
    **kwargs
        From pythonfmu: ``instance_name``, ``resources`` (the folder that holds
        :data:`~pneumaquad.interop.fmu_model.PARAMETERS_FILE` and
        :data:`~pneumaquad.interop.fmu_model.SETTINGS_FILE`), ``visible``, ``logger``.

    Attributes
    ----------
    valve_voltage : float
        Input [V].
    piston_position : float
        Input [m].
    piston_velocity : float
        Input [m/s].
    """

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        if self.resources is None:
            raise ValueError("the actuator FMU needs its resources folder (parameters and "
                             "settings)")
        folder = Path(self.resources)
        self.settings = FmuSettings.read(folder / SETTINGS_FILE)
        self._exported = load_actuator(folder / PARAMETERS_FILE)
        self.modelName = self.settings.model_name
        release_at_exit(folder, self.settings.model_name)
        self.description = (f"Pneumatic actuator (valve, cylinder, friction, supply) of "
                            f"parameter set {self.settings.parameter_set}: "
                            f"{self._exported.meta.description}")
        self.version = self.settings.pneumaquad_version
        self.default_experiment = DefaultExperiment(start_time=0.0,
                                                    step_size=self.settings.control_step)
        self._warn_on_other_version()
        self._parameters = parameter_variables(self._exported)
        self._values: dict[str, Any] = {}
        for variable in self._parameters:
            value = getattr_dotted(self._exported, variable.key)
            self._values[variable.name] = value if variable.index is None \
                else value[variable.index]
        for name, setting in SETTING_FIELDS.items():
            self._values[name] = getattr(self.settings, setting)
        self.valve_voltage = self._exported.valve.offset_voltage
        self.piston_position = self.settings.initial_position
        self.piston_velocity = 0.0
        self._initialised = False
        self._register_variables()
        self._set_up()

    # --- variables -----------------------------------------------------------------------
    @property
    def declared_variables(self) -> tuple[FmuVariable, ...]:
        """Every variable of the FMU, in the order of their value references."""
        return (*INPUTS, *OUTPUTS, *self._parameters, *SETTING_VARIABLES)

    def _register_variables(self) -> None:
        """Register inputs, outputs and parameters with pythonfmu (value references in
        the order of :attr:`declared_variables`)."""
        for variable in INPUTS:
            self.register_variable(Real(
                variable.name, causality=Fmi2Causality.input, description=variable.description,
                getter=lambda name=variable.name: getattr(self, name),
                setter=lambda value, name=variable.name: setattr(self, name, float(value))),
                nested=False)
        for variable in OUTPUTS:
            self.register_variable(Real(
                variable.name, causality=Fmi2Causality.output,
                variability=Fmi2Variability.continuous, description=variable.description,
                getter=lambda name=variable.name: self._read_output(name)), nested=False)
        for variable in (*self._parameters, *SETTING_VARIABLES):
            self.register_variable(_VARIABLE_TYPES[variable.kind](
                variable.name, causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.fixed, description=variable.description,
                getter=lambda name=variable.name: self._values[name],
                setter=lambda value, name=variable.name: self._set_parameter(name, value)),
                nested=False)

    def _set_parameter(self, name: str, value: Any) -> None:
        """Store a parameter's new value; refused once initialised (FMI ``fixed``)."""
        if self._initialised:
            raise FixedParameterError(f"{name} is a fixed parameter: set it before "
                                      "exitInitializationMode (or reset the FMU first)")
        self._values[name] = value

    def to_xml(self, model_options: dict[str, str] | None = None) -> Any:
        """The model description, completed with units, exact parameter start values and
        the initial unknowns (:func:`~pneumaquad.interop.fmu_model.complete_model_description`)."""
        root = super().to_xml(model_options or {})
        real_starts = {variable.name: self._values[variable.name]
                       for variable in (*self._parameters, *SETTING_VARIABLES)
                       if variable.kind == "real"}
        return complete_model_description(root, self.declared_variables, real_starts)

    # --- FMI life cycle ------------------------------------------------------------------
    def setup_experiment(self, start_time: float, stop_time: float | None = None,
                         tolerance: float | None = None) -> None:
        """Nothing to set up: the actuator does not depend on the experiment's times."""

    def exit_initialization_mode(self) -> None:
        """Validate the parameters and start from rest at the present inputs.

        Raises
        ------
        ParameterError
            A parameter outside its range, an unknown model name, or a
            ``piston_position`` outside the stroke (the message names each).
        """
        self._set_up()
        self._initialised = True
        self._load_kernel()

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Advance the actuator from ``current_time`` by ``step_size`` [s] with the inputs
        held. False (FMI discard) for an input that is not finite or a negative step (the
        state is left as it was), or when the state has become non-finite (the kernel step
        was too long for the chambers; the FMU cannot go on)."""
        voltage, position, velocity = self.valve_voltage, self.piston_position, \
            self.piston_velocity
        if not (math.isfinite(voltage + position + velocity) and step_size >= 0.0):
            self.log(f"at t = {current_time:g} s: step {step_size!r} s with inputs "
                     f"valve_voltage={voltage!r}, piston_position={position!r}, "
                     f"piston_velocity={velocity!r}; expected finite inputs and a step "
                     "of at least 0 s", Fmi2Status.error)
            return False
        if step_size == 0.0:
            return True
        count = max(1, math.ceil(step_size / self._control_step - STEP_SLACK))
        kernel_step = step_size / count
        stroke = self._stroke
        state, out = self._state_record, self._output_record
        self._commands[0] = voltage
        cap_flow = rod_flow = supply_flow = 0.0
        for _ in range(count):
            position = min(max(position, 0.0), stroke)
            moving = velocity
            if (position <= 0.0 and moving < 0.0) or (position >= stroke and moving > 0.0):
                moving = 0.0  # on an end stop, pushed into it: the piston does not move
            self._positions[0] = position
            self._velocities[0] = moving
            step_actuators(self._params, self._state, self._commands, self._positions,
                           self._velocities, kernel_step, self._substeps, self._supply,
                           self._outputs)
            cap_flow += float(out["cap_mass_flow"])
            rod_flow += float(out["rod_mass_flow"])
            supply_flow += float(out["supply_mass_flow"])
            position = state["position"]
        self._mean_flows = (cap_flow / count, rod_flow / count, supply_flow / count)
        if not math.isfinite(state["cap_pressure"] + state["rod_pressure"] + state["cap_mass"]
                             + state["rod_mass"]):
            self.log(f"the actuator's state is not finite at t = {current_time + step_size:g}"
                     " s (a kernel step too long for the chambers: lower "
                     "simulation.control_step or raise simulation.substeps)", Fmi2Status.error)
            return False
        return True

    def output_values(self) -> dict[str, float]:
        """The outputs now (:data:`~pneumaquad.interop.fmu_model.OUTPUTS`), name -> SI
        value."""
        return {variable.name: self._read_output(variable.name) for variable in OUTPUTS}

    def _read_output(self, name: str) -> float:
        """One output [SI]: the state and kernel outputs at the end of the last step, the
        flows averaged over it."""
        state, out = self._state_record, self._output_record
        if name == "piston_force":
            return float(out["pneumatic_force"] - out["friction_force"])
        if name in _STATE_OUTPUTS:
            return float(state[name])
        if name in _KERNEL_OUTPUTS:
            return float(out[name])
        if name in _MEAN_FLOWS:
            return self._mean_flows[_MEAN_FLOWS.index(name)]
        if name == "available_supply_pressure":
            if self._supply_pressure is not None:
                return self._supply_pressure
            return float(supply_pressure_now(self._params[0], self._supply[0]))
        raise KeyError(f"{name} is not an output of the actuator FMU")

    # --- the actuator --------------------------------------------------------------------
    def _set_up(self) -> None:
        """Validate the parameters, pack them, and put the actuator at rest at the
        ``piston_position`` input with the initial pressures; outputs of that state."""
        actuator = self._validated_parameters()
        settings = {name: self._validated_setting(name) for name in SETTING_FIELDS}
        stroke = actuator.cylinder.stroke
        position = self.piston_position
        if not 0.0 <= position <= stroke:
            raise ParameterError([Problem("piston_position", position,
                                          f"should be within [0, cylinder.stroke] = "
                                          f"[0, {stroke:g} m] at initialisation")],
                                 source="FMU inputs")
        self._control_step = settings["simulation.control_step"]
        self._substeps = settings["simulation.substeps"]
        self._params = pack_parameter_array([actuator])
        self._state = np.zeros(1, ACTUATOR_STATE_DTYPE)
        initial_state(self._params[0], position, settings["initial.cap_pressure"],
                      settings["initial.rod_pressure"], out=self._state[0])
        self._supply = supply_state(actuator)
        self._outputs = new_outputs(1)
        self._commands = np.array([self.valve_voltage], dtype=np.float64)
        self._positions = np.array([position], dtype=np.float64)
        self._velocities = np.array([self.piston_velocity], dtype=np.float64)
        self._stroke = stroke
        self._state_record, self._output_record = self._state[0], self._outputs[0]
        state_outputs(self._params[0], self._state_record, position, self._output_record)
        self._output_record["friction_force"] = friction_of(
            self._params[0], self.piston_velocity, self._state_record["bristle_deflection"])
        self._mean_flows = (0.0, 0.0, 0.0)
        # an ideal supply delivers its set point throughout; a tank's is read each time
        self._supply_pressure = (actuator.supply.supply_pressure
                                 if actuator.supply.model == "ideal" else None)

    def _load_kernel(self) -> None:
        """Have numba load (or compile) the kernel now, with one step on copies of the
        arrays, so that the first ``doStep`` takes no longer than the others."""
        step_actuators(self._params, self._state.copy(), self._commands, self._positions,
                       self._velocities, self._control_step, self._substeps,
                       self._supply.copy(), self._outputs.copy())

    def _validated_parameters(self) -> ActuatorParameters:
        """The parameter set with the FMU parameters' present values, validated."""
        changes = parameter_changes(self._parameters, self._values)
        return validated_update(self._exported, changes, source="FMU parameters")

    def _validated_setting(self, name: str) -> Any:
        """An FMU setting's present value, checked against its range."""
        value = self._values[name]
        try:
            return _SETTING_TYPES[name].validate_python(value)
        except ValidationError as error:
            message = error.errors()[0]["msg"].removeprefix("Value error, ")
            raise ParameterError([Problem(name, value, message)],
                                 source="FMU parameters") from None

    def _warn_on_other_version(self) -> None:
        """Log a warning when the installed pneumaquad is not the exporting one."""
        from pneumaquad import __version__

        if __version__ != self.settings.pneumaquad_version:
            self.log(f"this FMU was exported by pneumaquad {self.settings.pneumaquad_version} "
                     f"and runs with pneumaquad {__version__}", Fmi2Status.warning)


guard_entry_points(ActuatorSlave)


def getattr_dotted(model: Any, key: str) -> Any:
    """The value at a dotted key of a parameter model (``"supply.supply_pressure"``)."""
    for part in key.split("."):
        model = getattr(model, part)
    return model
