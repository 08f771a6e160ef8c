"""The world around the robot: ground, block obstacle, ramp, hill and rough-terrain field.

Environments (selectable per run):

``flat``   ground plane only;
``block``  a box obstacle ahead of the robot (thesis Fig. 4);
``ramp``   the 1.2 × 1.2 × 0.019 m plate of App. C.2.3, tilted up from the ground;
``rough``  a field of square cells, a seeded random half of them raised by random
           heights (the thesis's "HALF RANDOM" map, App. C.2.4);
``hill``   the ramp, a flat top level with its upper edge, and the ramp mirrored down
           again (a climb and a descent at the ramp's slope).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from pneumaquad.params.robot_schema import ContactParameters, EnvironmentParameters

from .frames import euler_zyx_matrix, rotation_to_quaternion

__all__ = ["ENVIRONMENTS", "WORLD_CONTYPE", "add_environment"]

ENVIRONMENTS = ("flat", "block", "ramp", "rough", "hill")

#: Collision bits: world geoms collide with the robot, not with each other; robot
#: geoms collide with the world, not with each other (SrLib SetSelfCollision(false)).
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 2

_GROUND_RGBA = (0.55, 0.55, 0.5, 1.0)
_OBSTACLE_RGBA = (0.65, 0.5, 0.35, 1.0)


def _static_box(
    spec: mujoco.MjSpec,
    name: str,
    half_size: tuple[float, float, float],
    position: tuple[float, float, float],
    friction: float,
    contact: ContactParameters,
    quaternion: np.ndarray | None = None,
) -> None:
    geom = spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(half_size),
        pos=list(position),
        rgba=list(_OBSTACLE_RGBA),
    )
    if quaternion is not None:
        geom.quat = list(quaternion)
    _world_contact(geom, friction, contact)


def _world_contact(geom: mujoco.MjsGeom, friction: float, contact: ContactParameters) -> None:
    geom.contype = WORLD_CONTYPE
    geom.conaffinity = WORLD_CONAFFINITY
    geom.friction = [friction, 0.005, 0.0001]
    geom.solref = [contact.time_constant, contact.damping_ratio]


def add_environment(
    spec: mujoco.MjSpec,
    environment: str,
    parameters: EnvironmentParameters,
    contact: ContactParameters,
    seed: int = 0,
) -> None:
    """Add the ground and the chosen obstacles to ``spec``'s world body.

    Parameters
    ----------
    spec : mujoco.MjSpec
        Model being built.
    environment : str
        One of :data:`ENVIRONMENTS`.
    parameters : EnvironmentParameters
        Sizes and positions [m], ramp slope [rad], rough-field settings.
    contact : ContactParameters
        Ground friction (thesis: 5.0) and contact softness.
    seed : int
        Seed of the rough field's ``numpy.random.Generator``.
    """
    if environment not in ENVIRONMENTS:
        raise ValueError(f"environment {environment!r} should be one of {ENVIRONMENTS}")
    ground = spec.worldbody.add_geom(
        name="ground",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.05],
        rgba=list(_GROUND_RGBA),
    )
    ground.material = "grid"
    _world_contact(ground, contact.ground_friction, contact)
    friction = contact.ground_friction
    if environment == "block":
        sx, sy, sz = parameters.block_size
        x, y, z = parameters.block_position
        _static_box(spec, "block", (sx / 2, sy / 2, sz / 2), (x + sx / 2, y, z + sz / 2),
                    friction, contact)
    elif environment in ("ramp", "hill"):
        sx, sy, sz = parameters.ramp_size
        x, y, z = parameters.ramp_position
        slope = parameters.ramp_slope
        rotation = euler_zyx_matrix((0.0, -slope, 0.0))
        # Lower edge on the ground at x: the plate's centre sits half a length up the slope.
        centre = (
            x + 0.5 * sx * math.cos(slope) - 0.5 * sz * math.sin(slope),
            y,
            z + 0.5 * sx * math.sin(slope) + 0.5 * sz * math.cos(slope),
        )
        _static_box(spec, "ramp", (sx / 2, sy / 2, sz / 2), centre, friction, contact,
                    rotation_to_quaternion(rotation))
        if environment == "hill":
            _add_hill_top_and_descent(spec, parameters, centre, rotation, friction, contact)
    elif environment == "rough":
        _add_rough_field(spec, parameters, contact, seed)


def _add_hill_top_and_descent(spec: mujoco.MjSpec, parameters: EnvironmentParameters,
                              centre: tuple[float, float, float], rotation: np.ndarray,
                              friction: float, contact: ContactParameters) -> None:
    """The hill's flat top (``hill_top_length`` long, level with the ramp plate's upper
    edge) and its way down: the ramp plate mirrored about the top's middle."""
    sx, sy, sz = parameters.ramp_size
    slope = parameters.ramp_slope
    corner = np.asarray(centre) + rotation @ np.array([sx / 2, 0.0, sz / 2])
    top = parameters.hill_top_length
    middle = corner[0] + top / 2
    _static_box(spec, "hill_top", (top / 2, sy / 2, corner[2] / 2),
                (middle, centre[1], corner[2] / 2), friction, contact)
    descent = euler_zyx_matrix((0.0, slope, 0.0))
    _static_box(spec, "descent", (sx / 2, sy / 2, sz / 2),
                (2 * middle - centre[0], centre[1], centre[2]), friction, contact,
                rotation_to_quaternion(descent))


def _add_rough_field(
    spec: mujoco.MjSpec, parameters: EnvironmentParameters, contact: ContactParameters, seed: int
) -> None:
    generator = np.random.default_rng(seed)
    cell = parameters.rough_cell
    count_x = max(1, round(parameters.rough_size[0] / cell))
    count_y = max(1, round(parameters.rough_size[1] / cell))
    raised = generator.random((count_x, count_y)) < parameters.rough_fill
    heights = generator.uniform(0.25, 1.0, (count_x, count_y)) * parameters.rough_max_height
    x0, y0 = parameters.rough_position
    for i in range(count_x):
        for j in range(count_y):
            if not raised[i, j]:
                continue
            height = float(heights[i, j])
            centre = (x0 + (i + 0.5) * cell, y0 + (j + 0.5 - count_y / 2) * cell, height / 2)
            _static_box(spec, f"rough_{i}_{j}", (cell / 2, cell / 2, height / 2), centre,
                        contact.ground_friction, contact)
