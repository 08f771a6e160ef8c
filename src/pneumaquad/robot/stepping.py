"""The stepping loop of the coupled simulation, compiled, with MuJoCo called from inside.

``mj_step`` is looked up in MuJoCo's shared library through ``ctypes`` and called from a
numba loop with the raw ``mjModel*``/``mjData*`` addresses, so a chunk of control steps
runs without returning to Python: one call per chunk instead of two Python calls per
step. The function address is a run-time argument, called through a small intrinsic
(an ``inttoptr`` cast), so the loop holds no process-specific constant and numba's
on-disk cache works for it like for the rest of the package.
"""

from __future__ import annotations

import ctypes
import glob
import os

import mujoco
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from pneumaquad.jit import compiled

from .coupling import robot_control_step

__all__ = ["MJ_STEP_ADDRESS", "advance_chunk", "mujoco_step_function"]


def _load_mj_step():
    folder = os.path.dirname(mujoco.__file__)
    candidates = sorted(glob.glob(os.path.join(folder, "libmujoco.so*"))) + sorted(
        glob.glob(os.path.join(folder, "libmujoco*.dylib"))
    )
    if not candidates:
        raise RuntimeError(f"MuJoCo's shared library was not found in {folder}")
    library = ctypes.CDLL(candidates[0])
    function = library.mj_step
    function.argtypes = [ctypes.c_uint64, ctypes.c_uint64]
    function.restype = None
    return function


mujoco_step_function = _load_mj_step()
#: Address of ``mj_step(const mjModel*, mjData*)`` in this process.
MJ_STEP_ADDRESS = ctypes.cast(mujoco_step_function, ctypes.c_void_p).value


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
def advance_chunk(
    step_address: int,
    step_count: int,
    model_address: int,
    data_address: int,
    physics_steps: int,
    reference_table,
    reference_start: int,
    tendon_length,
    tendon_velocity,
    tendon_ids,
    actuator_ids,
    control,
    tendon_frictionloss,
    tendon_damping,
    linkage,
    seal,
    mujoco_friction: bool,
    params,
    state,
    supply,
    outputs,
    gains,
    gain_scale,
    extra,
    pid_state,
    force_reference,
    reference_angles,
    open_loop_voltage,
    commands,
    positions,
    velocities,
    reference_positions,
    control_step: float,
    substeps: int,
):
    """Run ``step_count`` control steps: controllers + actuators, then MuJoCo steps.

    Row ``reference_start + k`` of ``reference_table`` (clamped to its last row) is the
    joint-angle reference of step k; an empty table keeps ``reference_angles`` as set.
    """
    rows = reference_table.shape[0]
    for k in range(step_count):
        if rows > 0:
            row = min(reference_start + k, rows - 1)
            for i in range(reference_angles.shape[0]):
                reference_angles[i] = reference_table[row, i]
        robot_control_step(
            tendon_length, tendon_velocity, tendon_ids, actuator_ids, control,
            tendon_frictionloss, tendon_damping, linkage, seal, mujoco_friction, params,
            state, supply, outputs, gains, gain_scale, extra, pid_state, force_reference,
            reference_angles, open_loop_voltage, commands, positions, velocities,
            reference_positions, control_step, substeps,
        )
        for _ in range(physics_steps):
            _call_step(step_address, model_address, data_address)
