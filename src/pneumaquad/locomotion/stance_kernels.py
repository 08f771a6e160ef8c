"""Compiled arithmetic of the force-controlled stance, once per control chunk.

:class:`.stance_control.StanceController` sets every stance leg's cylinder force
set-points from the simulation's state (module docstring of :mod:`.stance_control`); the
arithmetic is here as compiled functions on MuJoCo's own arrays (views of the simulation's
``MjModel`` and ``MjData``, gathered once in a :class:`StanceViews`) and a
:class:`StanceWorkspace` of scratch, so a chunk costs no Python loop and no allocation:

1. the legs' load shares at the gait phase (:func:`load_shares_into`);
2. the measured centre of mass (:func:`centre_of_mass_into`) and the least-variation
   normal forces about it (:func:`normal_forces_into`, the 3×3 normal equations solved
   directly; a system too ill-conditioned for that, fewer than three loaded feet, is left
   to :func:`.stance_control.desired_normal_forces`' least squares);
3. the cylinder force set-points of the loaded legs (:func:`cylinder_forces_into`), the
   vertical row of each foot's world Jacobian computed as MuJoCo's ``mj_jacSite`` does
   (from ``cdof`` and ``subtree_com``) and the linkage moment arms of
   :func:`pneumaquad.robot.linkage.moment_arm`.

Units: SI (m, N, N·m, kg, s) and radians.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from pneumaquad.core.jit import compiled
from pneumaquad.robot.feedback import leg_dof_addresses
from pneumaquad.robot.kinematics import solve_3x3
from pneumaquad.robot.simulation import RobotSimulation

from .feedback_kernels import GaitTiming, leg_phase

__all__ = ["SMALLEST_INVERSE_CONDITION", "StanceViews", "StanceWorkspace",
           "centre_of_mass_into", "cylinder_forces_into", "load_shares_into",
           "normal_forces_into", "stance_step", "stance_views", "stance_workspace"]

Array = NDArray[np.float64]

#: Lower bound on 1/condition of the 3×3 load-sharing system (|det| / ‖A‖_F³) above which
#: it is solved directly; below, the least-squares answer is taken (rank-deficient systems
#: of fewer than three loaded feet, nearly collinear feet).
SMALLEST_INVERSE_CONDITION = 1e-7


class StanceViews(NamedTuple):
    """What the stance arithmetic reads of one simulation: views of its MuJoCo arrays
    (valid for the simulation's life) and constant indices and geometry."""

    site_positions: Array  # data.site_xpos (sites, 3) [m]
    foot_sites: NDArray[np.int64]  # (legs,) site id of each foot
    body_mass: Array  # model.body_mass (bodies,) [kg]
    body_centres: Array  # data.xipos (bodies, 3) [m] centres of mass
    joint_positions: Array  # data.qpos
    joint_addresses: NDArray[np.int64]  # (legs, 3) qpos address of alpha, beta, gamma
    dof_motions: Array  # data.cdof (dofs, 6) motion axes in the centre-of-mass frame
    subtree_centres: Array  # data.subtree_com (bodies, 3) [m]
    foot_roots: NDArray[np.int64]  # (legs,) root body of each foot's body
    leg_dofs: NDArray[np.int64]  # (legs, 3) dof address of alpha, beta, gamma
    bias_forces: Array  # data.qfrc_bias (dofs,) [N·m at hinges]
    linkages: Array  # (legs, 3, 4) l1 [m], l3 [m], γ0 [rad], direction ±1 per joint
    total_mass: float  # [kg] sum of the body masses
    weight: float  # [N] the robot's weight


class StanceWorkspace(NamedTuple):
    """Scratch of the compiled stance arithmetic, allocated once by its owner."""

    centre: Array  # (2,) [m] ground projection of the centre of mass
    matrix: Array  # (3, 3) load-sharing normal equations
    target: Array  # (3,) their right-hand side [N, N·m]
    elimination: Array  # (3, 4) augmented matrix of the solve
    multipliers: Array  # (3,) their solution


def stance_views(simulation: RobotSimulation) -> StanceViews:
    """The :class:`StanceViews` of ``simulation``."""
    robot, model, data = simulation.robot, simulation.model, simulation.data
    legs = len(robot.legs)
    joints = np.array([robot.joint_names.index(f"{leg}_alpha") + np.arange(3)
                       for leg in robot.legs])
    linkages = np.empty((legs, 3, 4))
    for leg in range(legs):
        for k in range(3):
            link = robot.linkages[robot.joint_types[joints[leg, k]]]
            linkages[leg, k] = (link.child_pivot_radius, link.parent_pivot_radius,
                                link.included_angle_at_zero, link.direction)
    foot_sites = np.asarray(robot.foot_site_id, dtype=np.int64)
    return StanceViews(
        site_positions=data.site_xpos,
        foot_sites=foot_sites,
        body_mass=model.body_mass,
        body_centres=data.xipos,
        joint_positions=data.qpos,
        joint_addresses=np.asarray(robot.qpos_address, dtype=np.int64)[joints],
        dof_motions=data.cdof,
        subtree_centres=data.subtree_com,
        foot_roots=np.asarray(model.body_rootid[model.site_bodyid[foot_sites]],
                              dtype=np.int64),
        leg_dofs=np.array([leg_dof_addresses(robot, leg) for leg in robot.legs],
                          dtype=np.int64),
        bias_forces=data.qfrc_bias,
        linkages=linkages,
        total_mass=float(model.body_mass.sum()),
        weight=float(model.body_mass.sum() * np.linalg.norm(model.opt.gravity)),
    )


def stance_workspace() -> StanceWorkspace:
    """A fresh :class:`StanceWorkspace`."""
    return StanceWorkspace(np.zeros(2), np.zeros((3, 3)), np.zeros(3), np.zeros((3, 4)),
                           np.zeros(3))


@compiled
def load_shares_into(timing: GaitTiming, gait_time: float, rise: float, fall: float,
                     shares: Array) -> None:
    """Load share in [0, 1] of each leg at ``gait_time`` [s] into ``shares`` (legs,)
    (compiled :func:`.stance_control.load_shares` of :func:`.feedback_kernels.leg_phase`;
    ``rise`` and ``fall`` cycle fractions)."""
    touchdown = 1.0 - timing.duty_factor
    for leg in range(shares.shape[0]):
        phase = leg_phase(timing, gait_time, leg)
        share = min((phase - touchdown) / rise, (1.0 - phase) / fall)
        shares[leg] = min(max(share, 0.0), 1.0)


@compiled
def centre_of_mass_into(body_mass: Array, body_centres: Array, total_mass: float,
                        centre: Array) -> None:
    """Ground projection (x, y) [m] of the centre of mass of bodies of ``body_mass``
    [kg] at ``body_centres`` (bodies, 3) [m], of ``total_mass`` [kg] together, into
    ``centre`` (2,) (compiled :func:`pneumaquad.gait.stability.centre_of_mass`)."""
    for axis in range(2):
        moment = 0.0
        for body in range(body_mass.shape[0]):
            moment += body_mass[body] * body_centres[body, axis]
        centre[axis] = moment / total_mass


@compiled
def normal_forces_into(site_positions: Array, foot_sites: NDArray[np.int64], centre: Array,
                       total_load: float, weights: Array, workspace: StanceWorkspace,
                       forces: Array) -> bool:
    """Normal forces [N] of the feet carrying ``total_load`` [N] about ``centre`` (2,) [m]
    into ``forces`` (legs,) (compiled :func:`.stance_control.desired_normal_forces`).

    The feet are ``site_positions[foot_sites]`` [m] (x, y used), weighted by ``weights``
    (legs,) (feet of weight 0 carry nothing). The 3×3 normal equations of the least
    Σ Fᵢ²/wᵢ distribution are solved by elimination. Returns False, ``forces`` undefined,
    where they are too ill-conditioned for that (1/condition below
    :data:`SMALLEST_INVERSE_CONDITION`: fewer than three loaded feet); the caller then
    takes the least-squares answer.
    """
    matrix, target = workspace.matrix, workspace.target
    legs = foot_sites.shape[0]
    loaded = 0
    for leg in range(legs):
        forces[leg] = 0.0
        if weights[leg] > 0.0:
            loaded += 1
    if total_load <= 0.0 or loaded == 0:
        return True
    for r in range(3):
        for c in range(3):
            matrix[r, c] = 0.0
    for leg in range(legs):
        weight = weights[leg]
        if weight > 0.0:
            x = site_positions[foot_sites[leg], 0]
            y = site_positions[foot_sites[leg], 1]
            row = (1.0, x, y)
            for r in range(3):
                scaled = row[r] * weight
                matrix[r, 0] += scaled
                matrix[r, 1] += scaled * x
                matrix[r, 2] += scaled * y
    determinant = (matrix[0, 0] * (matrix[1, 1] * matrix[2, 2] - matrix[1, 2] * matrix[2, 1])
                   - matrix[0, 1] * (matrix[1, 0] * matrix[2, 2] - matrix[1, 2] * matrix[2, 0])
                   + matrix[0, 2] * (matrix[1, 0] * matrix[2, 1] - matrix[1, 1] * matrix[2, 0]))
    squares = 0.0
    for r in range(3):
        for c in range(3):
            squares += matrix[r, c] * matrix[r, c]
    if not abs(determinant) > SMALLEST_INVERSE_CONDITION * squares * math.sqrt(squares):
        return False
    target[0] = total_load
    target[1] = total_load * centre[0]
    target[2] = total_load * centre[1]
    multipliers = workspace.multipliers
    if not solve_3x3(matrix, target, workspace.elimination, multipliers):
        return False
    total = 0.0
    for leg in range(legs):
        weight = weights[leg]
        if weight > 0.0:
            x = site_positions[foot_sites[leg], 0]
            y = site_positions[foot_sites[leg], 1]
            share = weight * (multipliers[0] + x * multipliers[1] + y * multipliers[2])
            if share < 0.0:  # a pulling foot: the centre of mass outside the support
                share = 0.0
            forces[leg] = share
            total += share
    if total > 0.0:
        scale = total_load / total
        for leg in range(legs):
            forces[leg] *= scale
    return True


@compiled
def cylinder_forces_into(views: StanceViews, shares: Array, normal: Array,
                         set_points: Array) -> int:
    """Cylinder force set-points [N] of every leg of share > 0 into ``set_points``
    (3·legs,), three per such leg in leg order (compiled
    :func:`.stance_control.cylinder_forces_for_foot_force` of a vertical foot force
    ``normal`` (legs,) [N]).

    Each joint's torque ``bias − J_zᵀ·N`` [N·m] (MuJoCo's ``qfrc_bias``, J_z the vertical
    row of the foot's world Jacobian as ``mj_jacSite`` computes it) over its cylinder's
    moment arm [m]. Returns the loaded legs as bits (bit ``leg`` set for share > 0).
    """
    loaded = 0
    count = 0
    for leg in range(shares.shape[0]):
        if shares[leg] <= 0.0:
            continue
        loaded |= 1 << leg
        site, root = views.foot_sites[leg], views.foot_roots[leg]
        offset_x = views.site_positions[site, 0] - views.subtree_centres[root, 0]
        offset_y = views.site_positions[site, 1] - views.subtree_centres[root, 1]
        for k in range(3):
            dof = views.leg_dofs[leg, k]
            motion = views.dof_motions[dof]
            vertical = motion[5] + (motion[0] * offset_y - motion[1] * offset_x)  # [m/rad]
            linkage = views.linkages[leg, k]
            child, parent, included, direction = linkage[0], linkage[1], linkage[2], linkage[3]
            angle = views.joint_positions[views.joint_addresses[leg, k]]
            gamma = included + direction * angle
            pin = math.sqrt(child * child + parent * parent
                            - 2.0 * child * parent * math.cos(gamma))
            arm = direction * child * parent * math.sin(gamma) / pin  # [m/rad]
            set_points[count] = (views.bias_forces[dof] - vertical * normal[leg]) / arm
            count += 1
    return loaded


@compiled
def stance_step(views: StanceViews, timing: GaitTiming, gait_time: float, rise: float,
                fall: float, workspace: StanceWorkspace, shares: Array, normal: Array,
                set_points: Array) -> int:
    """Shares, normal forces and cylinder set-points of one chunk (compiled).

    :func:`load_shares_into` at ``gait_time`` [s] into ``shares`` (legs,), the robot's
    weight about its centre of mass (:func:`centre_of_mass_into`, into
    ``workspace.centre``) shared into ``normal`` (legs,) [N] (:func:`normal_forces_into`),
    and the set-points [N] of :func:`cylinder_forces_into`. Returns the loaded legs as bits,
    or -1 where the normal forces need the least-squares answer (set-points not filled).
    """
    load_shares_into(timing, gait_time, rise, fall, shares)
    centre_of_mass_into(views.body_mass, views.body_centres, views.total_mass,
                        workspace.centre)
    if not normal_forces_into(views.site_positions, views.foot_sites, workspace.centre,
                              views.weight, shares, workspace, normal):
        return -1
    return cylinder_forces_into(views, shares, normal, set_points)
