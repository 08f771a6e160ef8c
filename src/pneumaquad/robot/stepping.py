"""The stepping loop of the coupled simulation, compiled, with MuJoCo called from inside.

Each control step is ``mj_step1`` (kinematics, contacts and velocities of the present
state), the control step of :mod:`pneumaquad.robot.coupling` on those, then ``mj_step2``
(forces, accelerations, integration), and ``mj_step`` for any further physics steps of
the control step. A chunk ends with ``mj_step1``, MuJoCo's force stages (so contact forces are
those of the present contacts, with the last applied cylinder forces) and the actuators
brought to the end time, so between chunks MuJoCo's derived quantities, the piston
positions and the chamber states all belong to the same instant.

``mj_step1``, ``mj_step2`` and ``mj_step`` are looked up in MuJoCo's shared library
through ``ctypes`` and called from a numba loop with the raw ``mjModel*``/``mjData*``
addresses, so a chunk of control steps runs without returning to Python. The function
addresses are run-time arguments, called through a small intrinsic (an ``inttoptr``
cast), so the loop holds no process-specific constant and numba's on-disk cache works
for it like for the rest of the package.
"""

from __future__ import annotations

import ctypes
import platform
from pathlib import Path
from typing import NamedTuple

import mujoco
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from pneumaquad.core.jit import compiled

from .coupling import (
    ActuatorArrays,
    Controllers,
    Cylinders,
    MujocoBuffers,
    StepSettings,
    StepTrace,
    robot_control_step,
    sample_actuators,
)

__all__ = [
    "MJ_FORCE_STAGE_ADDRESSES",
    "MJ_STEP1_ADDRESS",
    "MJ_STEP2_ADDRESS",
    "MJ_STEP_ADDRESS",
    "MUJOCO_LIBRARY_NAMES",
    "STATUS_ACTUATOR",
    "STATUS_MUJOCO",
    "STATUS_OK",
    "UNSTABLE_WARNINGS",
    "UNSTABLE_WARNING_QUANTITIES",
    "MujocoStepper",
    "advance_chunk",
    "begin_step",
    "bring_to_present",
    "complete_step",
    "mujoco_library_path",
    "mujoco_step_function",
    "struct_address",
    "unstable_quantities",
]

#: Chunk outcomes returned by :func:`advance_chunk`.
STATUS_OK = 0
STATUS_MUJOCO = 1  # MuJoCo warned of a non-finite or huge qpos, qvel, qacc or ctrl
STATUS_ACTUATOR = 2  # a cylinder's piston or chamber state went non-finite

#: MuJoCo warnings that mean the simulation is unstable, and what each is about.
UNSTABLE_WARNING_QUANTITIES = {
    mujoco.mjtWarning.mjWARN_BADQPOS: "joint positions (qpos)",
    mujoco.mjtWarning.mjWARN_BADQVEL: "joint velocities (qvel)",
    mujoco.mjtWarning.mjWARN_BADQACC: "joint accelerations (qacc)",
    mujoco.mjtWarning.mjWARN_BADCTRL: "cylinder forces (ctrl)",
}
#: The same warnings as indices into ``data.warning`` (for the compiled loop).
UNSTABLE_WARNINGS = np.array([int(warning) for warning in UNSTABLE_WARNING_QUANTITIES])


def unstable_quantities(data: mujoco.MjData) -> str:
    """The quantities MuJoCo warned about, e.g. ``"joint accelerations (qacc)"``."""
    named = [name for warning, name in UNSTABLE_WARNING_QUANTITIES.items()
             if data.warning[warning].number > 0]
    return " and ".join(named) or "the state"


#: File name of MuJoCo's shared library in its Python wheels, per ``platform.system()``
#: (MuJoCo's own ``__init__`` loads ``mujoco.dll`` from the package folder on Windows).
MUJOCO_LIBRARY_NAMES = {
    "Linux": "libmujoco.so.{version}",
    "Darwin": "libmujoco.{version}.dylib",
    "Windows": "mujoco.dll",
}


def mujoco_library_path(system: str | None = None) -> Path:
    """Path of the MuJoCo shared library that the ``mujoco`` bindings load.

    The wheels place it beside the bindings in the ``mujoco`` package folder under the
    name :data:`MUJOCO_LIBRARY_NAMES` gives for the platform and ``mujoco.__version__``
    (other POSIX systems use the Linux name). The bindings expose no handle or path of
    their own, and ``ctypes.util.find_library("mujoco")`` searches the system's folders,
    where it finds nothing or another MuJoCo than the one the bindings use.
    """
    system = system or platform.system()
    name = MUJOCO_LIBRARY_NAMES.get(system, MUJOCO_LIBRARY_NAMES["Linux"])
    name = name.format(version=mujoco.__version__)
    folders = [Path(folder) for folder in mujoco.__path__]
    for folder in folders:
        if (folder / name).is_file():
            return folder / name
    raise RuntimeError(f"MuJoCo's shared library {name} was not found in "
                       f"{', '.join(map(str, folders))}")


def _mujoco_library() -> ctypes.CDLL:
    # the bindings have loaded this file already: the loader hands back the same library
    return ctypes.CDLL(str(mujoco_library_path()))


def struct_address(struct: mujoco.MjModel | mujoco.MjData) -> int:
    """Address of the ``mjModel``/``mjData`` that a bindings object wraps, for C calls.

    MuJoCo 4 offers no public attribute for it: ``_address`` is the one the bindings
    define for this (and MuJoCo's maintainers point users to it), so it is read here
    and nowhere else; tests/robot/test_stepping.py fails with this message if it goes.
    """
    try:
        return int(struct._address)
    except AttributeError:
        raise RuntimeError(
            f"mujoco {mujoco.__version__} no longer exposes {type(struct).__name__}._address"
            ", the raw struct pointer the compiled stepping loop passes to mj_step"
        ) from None


def _step_function(library: ctypes.CDLL, name: str):
    function = getattr(library, name)
    function.argtypes = [ctypes.c_uint64, ctypes.c_uint64]
    function.restype = None
    return function


_library = _mujoco_library()
mujoco_step_function = _step_function(_library, "mj_step")
#: Addresses of ``mj_step``, ``mj_step1`` and ``mj_step2(const mjModel*, mjData*)``.
MJ_STEP_ADDRESS = ctypes.cast(mujoco_step_function, ctypes.c_void_p).value
MJ_STEP1_ADDRESS = ctypes.cast(_step_function(_library, "mj_step1"), ctypes.c_void_p).value
MJ_STEP2_ADDRESS = ctypes.cast(_step_function(_library, "mj_step2"), ctypes.c_void_p).value
#: Addresses of the stages that complete ``mj_step1`` into ``mj_forward`` (actuator
#: forces, smooth accelerations, the constraint solve with the contact forces).
MJ_FORCE_STAGE_ADDRESSES = tuple(
    ctypes.cast(_step_function(_library, name), ctypes.c_void_p).value
    for name in ("mj_fwdActuation", "mj_fwdAcceleration", "mj_fwdConstraint"))


@intrinsic
def _call_step(typing_context, function_address, model_address, data_address):
    """Call ``void f(uint64, uint64)`` at ``function_address`` (mj_step)."""
    signature = types.void(types.uint64, types.uint64, types.uint64)

    def codegen(context, builder, sig, args):
        function_type = ir.FunctionType(ir.VoidType(), [ir.IntType(64), ir.IntType(64)])
        pointer = builder.inttoptr(args[0], function_type.as_pointer())
        builder.call(pointer, [args[1], args[2]])
        return context.get_dummy_value()

    return signature, codegen


@compiled
def _unstable(warning_counts, baseline) -> bool:
    for k in range(UNSTABLE_WARNINGS.shape[0]):
        if warning_counts[UNSTABLE_WARNINGS[k]] != baseline[k]:
            return True
    return False


class MujocoStepper(NamedTuple):
    """How the compiled loop calls MuJoCo for one simulation."""

    step_addresses: np.ndarray  # mj_step1, the second half (mj_step2 or mj_step), mj_step,
    #                             then mj_fwdActuation, mj_fwdAcceleration, mj_fwdConstraint
    model_address: int  # mjModel*
    data_address: int  # mjData*
    warning_counts: np.ndarray  # data.warning.number
    physics_steps: int  # MuJoCo steps per control step


@compiled
def begin_step(stepper: MujocoStepper, coupling) -> None:
    """``mj_step1`` (kinematics, contacts, velocities of the present state) unless it ran
    for this state already."""
    if coupling[0].fresh == 0:
        _call_step(stepper.step_addresses[0], stepper.model_address, stepper.data_address)


@compiled
def complete_step(stepper: MujocoStepper, coupling) -> None:
    """The rest of the control step with the inputs set: the second half (``mj_step2``, or
    ``mj_step`` for RK4) and any further physics steps."""
    addresses = stepper.step_addresses
    model, data = stepper.model_address, stepper.data_address
    _call_step(addresses[1], model, data)
    for _ in range(stepper.physics_steps - 1):
        _call_step(addresses[2], model, data)
    coupling[0].fresh = 0


@compiled
def bring_to_present(stepper: MujocoStepper, coupling) -> None:
    """``mj_step1`` and MuJoCo's force stages for the present state, unless done already:
    the contact forces read afterwards are those of the present contacts (``mj_step1``
    alone leaves the last step's solution in ``efc_force``, indexed by the new contact
    rows); the next ``mj_step2`` recomputes them anyway."""
    if coupling[0].fresh == 0:
        addresses = stepper.step_addresses
        model, data = stepper.model_address, stepper.data_address
        for stage in (0, 3, 4, 5):
            _call_step(addresses[stage], model, data)
        coupling[0].fresh = 1


@compiled(nogil=True)
def advance_chunk(stepper: MujocoStepper, step_count: int, reference_table,
                  reference_start: int, mujoco: MujocoBuffers, cylinders: Cylinders,
                  actuators: ActuatorArrays, controllers: Controllers, trace: StepTrace,
                  coupling, settings: StepSettings):
    """Run ``step_count`` control steps, then bring MuJoCo and the actuators to the end.

    Row ``reference_start + k`` of ``reference_table`` (clamped to its last row) is the
    joint-angle reference of step k; an empty table keeps the references as set. A new
    MuJoCo unstable-state warning (its automatic reset must be disabled) or a non-finite
    actuator state stops the chunk.

    Returns
    -------
    (int, int, int)
        Control steps completed, status (``STATUS_OK``, ``STATUS_MUJOCO`` or
        ``STATUS_ACTUATOR``) and the cylinder index of an actuator failure (else -1).
    """
    warning_counts = stepper.warning_counts
    baseline = np.empty(UNSTABLE_WARNINGS.shape[0], dtype=np.int64)
    for k in range(UNSTABLE_WARNINGS.shape[0]):
        baseline[k] = warning_counts[UNSTABLE_WARNINGS[k]]
    references = controllers.reference_angles
    rows = reference_table.shape[0]
    for k in range(step_count):
        if rows > 0:
            row = min(reference_start + k, rows - 1)
            for i in range(references.shape[0]):
                references[i] = reference_table[row, i]
        begin_step(stepper, coupling)
        bad = robot_control_step(mujoco, cylinders, actuators, controllers, trace, coupling,
                                 settings)
        if bad >= 0:
            return k, STATUS_ACTUATOR, bad
        complete_step(stepper, coupling)
        if _unstable(warning_counts, baseline):
            return k + 1, STATUS_MUJOCO, -1
    bring_to_present(stepper, coupling)
    if _unstable(warning_counts, baseline):
        return step_count, STATUS_MUJOCO, -1
    bad = sample_actuators(mujoco, cylinders, actuators, trace, coupling, settings)
    if bad >= 0:
        return step_count, STATUS_ACTUATOR, bad
    return step_count, STATUS_OK, -1
