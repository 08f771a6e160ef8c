"""The stepping loop of the coupled simulation, compiled, with MuJoCo called from inside.

``mj_step`` is taken from MuJoCo's shared library through ``ctypes`` and called from a
numba loop with the raw ``mjModel*``/``mjData*`` addresses, so a chunk of control steps
runs without returning to Python: one call per chunk instead of two Python calls per
step. The pointers are passed as 64-bit integers (same calling convention on the
supported 64-bit platforms). This small loop is compiled once per process (numba cannot
cache code that holds a ctypes function address); what it calls is cached as usual.
"""

from __future__ import annotations

import ctypes
import glob
import os

import mujoco
import numba

from .coupling import robot_control_step

__all__ = ["advance_chunk", "mujoco_step_function"]


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
_mj_step = mujoco_step_function


@numba.njit(error_model="numpy")
def advance_chunk(
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
    force_mean,
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
            state, supply, outputs, gains, gain_scale, extra, pid_state, force_mean,
            reference_angles, open_loop_voltage, commands, positions, velocities,
            reference_positions, control_step, substeps,
        )
        for _ in range(physics_steps):
            _mj_step(model_address, data_address)
