"""Validated robot parameter models: links, frames, linkages, controllers, simulation.

A robot file (``crr-quadruped.toml``) describes the Compact Rescue Robot the way the
thesis's SrLib listings do (App. C.2): capsule links with diameter, length and density,
joint frames given in the parent and the child link, four leg mountings on the thorax,
and the placement of the robot in the world. It adds what the thesis left to the reader:
the cylinder linkage of each joint, the per-joint controllers and the simulation settings.
All values are SI after validation (angles in rad).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import StrictBool, StrictInt
from pydantic import model_validator as _model_validator

from .schema import (
    MAX_LENGTH,
    MAX_MASS,
    MAX_TIME_CONSTANT,
    AbsolutePressure,
    Bounds,
    ControllerParameters,
    ControlStep,
    CrossFieldError,
    Damping,
    Length,
    Mass,
    Meta,
    NonNegativeLength,
    NonNegativeMass,
    Number,
    PositiveLength,
    QuantityField,
    StepCount,
    Time,
    _Model,
)

__all__ = [
    "JOINT_NAMES",
    "LEG_NAMES",
    "ContactParameters",
    "CylinderMounting",
    "EnvironmentParameters",
    "Frame",
    "JointControllerParameters",
    "JointParameters",
    "LinkParameters",
    "LinkageParameters",
    "RobotControllerParameters",
    "RobotParameters",
    "RobotSimulationParameters",
    "TestbedParameters",
]

#: Joint names from the shoulder out (thesis 3.1, App. C.2.1).
JOINT_NAMES = ("alpha", "beta", "gamma")
#: Leg names; SrLib's L1, R1, L2, R2 (App. C.2.2).
LEG_NAMES = ("front_left", "front_right", "rear_left", "rear_right")

#: Largest extent of an obstacle or its distance from the origin [m].
MAX_ENVIRONMENT_LENGTH = 100.0

#: Angle of a frame rotation in [-360 deg, 360 deg].
Angle = Annotated[
    float,
    QuantityField("angle"),
    Bounds(-2 * math.pi, 2 * math.pi, "rad", lower_inclusive=True,
           lower_text="-2π rad (-360°)", upper_text="2π rad (360°)"),
]
#: Joint limit in [-180 deg, 180 deg].
JointAngle = Annotated[
    float,
    QuantityField("angle"),
    Bounds(-math.pi, math.pi, "rad", lower_inclusive=True,
           lower_text="-π rad (-180°)", upper_text="π rad (180°)"),
]
#: Position coordinate in [-10 m, 10 m].
Coordinate = Annotated[Length, Bounds(-MAX_LENGTH, MAX_LENGTH, "m", lower_inclusive=True)]
#: Obstacle position coordinate in [-100 m, 100 m].
EnvironmentCoordinate = Annotated[
    Length, Bounds(-MAX_ENVIRONMENT_LENGTH, MAX_ENVIRONMENT_LENGTH, "m", lower_inclusive=True)
]
#: Obstacle extent in (0, 100 m].
EnvironmentLength = Annotated[Length, Bounds(0.0, MAX_ENVIRONMENT_LENGTH, "m")]
#: Density in (0, 30000 kg/m^3] (osmium, the densest element, is 22600).
Density = Annotated[float, QuantityField("density"), Bounds(0.0, 30000.0, "kg/m^3")]
#: Principal moment of inertia in (0, 1000 kg m^2].
Inertia = Annotated[float, QuantityField("inertia"), Bounds(0.0, 1000.0, "kg*m^2")]
#: Colour component in [0, 1].
ColourComponent = Annotated[Number, Bounds(0.0, 1.0, lower_inclusive=True)]
#: Gain multiplier in [0, 100].
GainScale = Annotated[Number, Bounds(0.0, 100.0, lower_inclusive=True)]
#: Friction coefficient in [0, 10].
FrictionCoefficient = Annotated[Number, Bounds(0.0, 10.0, lower_inclusive=True)]


class Frame(_Model):
    """A rigid transform as SrLib writes it: ``EulerZYX(Vec3(a, b, c), Vec3(x, y, z))``.

    ``rotation_zyx`` = (a, b, c) [rad] gives R = Rz(a)·Ry(b)·Rx(c); ``position`` [m].
    """

    rotation_zyx: tuple[Angle, Angle, Angle]
    position: tuple[Coordinate, Coordinate, Coordinate]


class LinkParameters(_Model):
    """A capsule link (SrLib ``SetDimension(diameter, length)``, ``UpdateInertia(density)``).

    ``length`` is the cylindrical part along the link's z axis; the hemispherical caps
    add ``diameter/2`` at each end. ``mass`` and ``inertia`` (principal moments about the
    link frame axes [kg m^2]) override the density estimate (thesis 5.6.1, 6.6.2).
    """

    diameter: PositiveLength
    length: NonNegativeLength
    density: Density
    collision_length: NonNegativeLength | None = None
    mass: Annotated[Mass, Bounds(0.0, MAX_MASS, "kg")] | None = None
    inertia: tuple[Inertia, Inertia, Inertia] | None = None
    color: tuple[ColourComponent, ColourComponent, ColourComponent] = (0.7, 0.7, 0.7)


class JointParameters(_Model):
    """A revolute joint: its frame in the parent and in the child link, limits [rad]."""

    parent_frame: Frame | None = None
    child_frame: Frame
    lower_limit: JointAngle
    upper_limit: JointAngle
    damping: Damping = 0.0

    @_model_validator(mode="after")
    def _limits(self) -> JointParameters:
        if not self.lower_limit < self.upper_limit:
            raise CrossFieldError(
                [("upper_limit", self.upper_limit, "should be above lower_limit")]
            )
        return self


class LegParameters(_Model):
    """Link frames of one leg (App. C.2.1): coxa (two capsules welded), femur, tibia."""

    coxa_weld_parent_frame: Frame
    coxa_weld_child_frame: Frame
    alpha: JointParameters
    beta: JointParameters
    gamma: JointParameters


class LinkageParameters(_Model):
    """Cylinder between two pivots of a joint (thesis Fig. 34–36, eq 5.2.1–5.2.6).

    The barrel pivot sits on the parent link at ``parent_pivot_radius`` (l3) from the joint
    axis, the rod-end pin on the child link at ``child_pivot_radius`` (l1); ``included
    angle`` γ between the two at the axis is ``included_angle_at_zero + direction·θ``;
    the pin-to-pin length is l2 + x with ``retracted_length`` = l2. When only the parent
    radius is given, the other three are designed so that the stroke spans the joint's
    range exactly with γ centred on 90° (:func:`pneumaquad.robot.linkage.design_linkage`).
    """

    parent_pivot_radius: PositiveLength
    child_pivot_radius: PositiveLength | None = None
    included_angle_at_zero: Angle | None = None
    retracted_length: PositiveLength | None = None
    direction: Literal[1, -1]
    axial_offset: Coordinate = 0.0
    moving_mass: NonNegativeMass

    @_model_validator(mode="after")
    def _all_or_none(self) -> LinkageParameters:
        given = [
            self.child_pivot_radius is not None,
            self.included_angle_at_zero is not None,
            self.retracted_length is not None,
        ]
        if any(given) and not all(given):
            raise CrossFieldError(
                [
                    (
                        "child_pivot_radius",
                        self.child_pivot_radius,
                        "child_pivot_radius, included_angle_at_zero and retracted_length "
                        "should be given together (measured linkage) or all left out "
                        "(designed from the stroke and the joint range)",
                    )
                ]
            )
        return self


class CylinderMounting(_Model):
    """Which actuator parameter set drives each joint type, and the robot's shared supply.

    ``supply_pressure`` [Pa absolute], when given, is the regulated supply of every
    cylinder (the robot's one regulator) in place of each actuator file's
    ``supply.supply_pressure``; e.g. ``--set 'actuators.supply_pressure="45 psig"'``.
    """

    alpha: str
    beta: str
    gamma: str
    supply_pressure: AbsolutePressure | None = None

    def actuator_overrides(self) -> list[str]:
        """``--set`` items that load the actuator files with this robot's supply."""
        if self.supply_pressure is None:
            return []
        return [f'supply.supply_pressure="{self.supply_pressure!r} Pa"']


class JointControllerParameters(ControllerParameters):
    """PID on piston position (the robot's linear potentiometers, thesis 5.2) + extras.

    ``gain_scale`` multiplies Kp, Ki and Kd (the thesis's alpha gain −25 %, 5.5.2.4);
    ``force_feedback_gain`` [V/N] feeds back the net pneumatic force's deviation from its
    low-pass mean (time constant ``force_feedback_time_constant``), adding damping from
    the pressure sensors without a steady-state error.
    """

    gain_scale: GainScale = 1.0
    force_feedback_gain: Annotated[
        float, QuantityField("voltage_per_force"), Bounds(0.0, 1.0, "V/N", lower_inclusive=True)
    ] = 0.0
    force_feedback_time_constant: Annotated[Time, Bounds(0.0, MAX_TIME_CONSTANT, "s")] = 0.05


class RobotControllerParameters(_Model):
    """Joint controllers per joint type, and stance/swing gain scales for scheduling."""

    alpha: JointControllerParameters
    beta: JointControllerParameters
    gamma: JointControllerParameters
    stance_gain_scale: GainScale = 1.0
    swing_gain_scale: GainScale = 1.0


class ContactParameters(_Model):
    """Friction coefficients (SrLib ``SetFriction``, App. C.2) and MuJoCo contact softness."""

    ground_friction: FrictionCoefficient
    foot_friction: FrictionCoefficient
    body_friction: FrictionCoefficient = 1.0
    time_constant: Annotated[Time, Bounds(0.0, 1.0, "s")] = 0.005
    damping_ratio: Annotated[Number, Bounds(0.0, 100.0)] = 1.0
    #: MuJoCo ``impratio``: impedance of the friction rows relative to the normal ones
    #: (elliptic cones); above 1 a loaded contact creeps less under tangential force.
    friction_impedance_ratio: Annotated[Number, Bounds(1.0, 1000.0, lower_inclusive=True)] = 1.0
    #: MuJoCo ``cone``: the friction cone of every contact. ``"elliptic"`` (one row per
    #: friction direction, exact Coulomb cone); ``"pyramidal"`` (MuJoCo's default: two rows
    #: per direction, a polygonal approximation of the cone).
    friction_cone: Literal["elliptic", "pyramidal"] = "elliptic"


class EnvironmentParameters(_Model):
    """Obstacles: block, ramp (App. C.2.3: 1.2 × 1.2 × 0.019 m), rough-terrain field."""

    block_size: tuple[EnvironmentLength, EnvironmentLength, EnvironmentLength]
    block_position: tuple[EnvironmentCoordinate, EnvironmentCoordinate, EnvironmentCoordinate]
    ramp_size: tuple[EnvironmentLength, EnvironmentLength, EnvironmentLength]
    ramp_position: tuple[EnvironmentCoordinate, EnvironmentCoordinate, EnvironmentCoordinate]
    ramp_slope: Annotated[
        float,
        QuantityField("angle"),
        Bounds(-math.pi / 3, math.pi / 3, "rad", lower_inclusive=True,
               lower_text="-π/3 rad (-60°)", upper_text="π/3 rad (60°)"),
    ]
    rough_size: tuple[EnvironmentLength, EnvironmentLength]
    rough_position: tuple[EnvironmentCoordinate, EnvironmentCoordinate]
    rough_max_height: PositiveLength
    rough_cell: PositiveLength
    rough_fill: Annotated[Number, Bounds(0.0, 1.0, lower_inclusive=True)] = 0.5


class TestbedParameters(_Model):
    """Two-legged testbed (thesis 3.1.2): the rear of the body rolls on passive wheels.

    Two wheels on one axle under the rear end of the thorax, free to spin; the axle hangs
    ``axle_drop`` below the thorax axis.
    """

    wheel_radius: PositiveLength
    wheel_width: PositiveLength
    wheel_mass: Annotated[Mass, Bounds(0.0, MAX_MASS, "kg")]
    axle_drop: NonNegativeLength
    track_width: PositiveLength


class RobotSimulationParameters(_Model):
    """Coupled-simulation settings.

    ``control_step`` [s] is the period of the controllers and of the pneumatic kernel
    (``substeps`` Heun steps inside); MuJoCo takes ``physics_steps`` steps per control
    step. ``seal_friction`` chooses where cylinder friction lives: ``"mujoco"`` (dry
    friction in the constraint solver, Stribeck breakaway updated each step) or
    ``"actuator"`` (the actuator file's force law, applied through the motor).

    MuJoCo's constraint solver: ``solver`` (MuJoCo ``solver``: Newton, conjugate gradient
    or projected Gauss-Seidel), at most ``solver_iterations`` iterations per step
    (``iterations``), stopping early once the relative cost improvement falls below
    ``solver_tolerance`` (``tolerance``, dimensionless; 0 runs every iteration);
    ``noslip_iterations`` of MuJoCo's no-slip post-processing (0: off).
    ``constraint_islands``: MuJoCo's island discovery (the constraint rows split into
    independent groups solved one by one; false sets the ``island`` disable flag).
    ``piston_inertia``: where MuJoCo holds each cylinder's moving piston/rod mass m:
    ``"tendon"``, the cylinder tendon's armature (exact, m·ẋ² follows the moment arm;
    MuJoCo computes the tendon's velocity-product force every step), or ``"joint"``, the
    hinge's armature m·⟨r²⟩ with ⟨r²⟩ the mean squared moment arm over the joint's range
    (a constant reflected inertia, cheaper).
    """

    control_step: ControlStep
    substeps: StepCount
    physics_steps: StepCount = 1
    integrator: Literal["implicitfast", "implicit", "euler", "rk4"] = "implicitfast"
    seal_friction: Literal["mujoco", "actuator"] = "mujoco"
    noslip_iterations: Annotated[StrictInt, Bounds(0, 1000, lower_inclusive=True)] = 0
    solver: Literal["newton", "cg", "pgs"] = "newton"
    solver_iterations: Annotated[StrictInt, Bounds(1, 10000, lower_inclusive=True)] = 50
    solver_tolerance: Annotated[Number, Bounds(0.0, 1.0, lower_inclusive=True)] = 1e-8
    constraint_islands: StrictBool = True
    piston_inertia: Literal["tendon", "joint"] = "tendon"
    recording_every: Annotated[StrictInt, Bounds(1, 1_000_000, lower_inclusive=True)] = 10


class RobotParameters(_Model):
    """A complete robot parameter set (see module docstring)."""

    meta: Meta
    actuators: CylinderMounting
    thorax: LinkParameters
    coxa1: LinkParameters
    coxa2: LinkParameters
    femur: LinkParameters
    tibia: LinkParameters
    leg: LegParameters
    mounts: dict[Literal[LEG_NAMES], Frame]  # type: ignore[valid-type]
    placement: Frame
    linkages: dict[Literal[JOINT_NAMES], LinkageParameters]  # type: ignore[valid-type]
    contact: ContactParameters
    environment: EnvironmentParameters
    controller: RobotControllerParameters
    simulation: RobotSimulationParameters
    testbed: TestbedParameters

    @_model_validator(mode="after")
    def _complete(self) -> RobotParameters:
        problems = []
        for name in LEG_NAMES:
            if name not in self.mounts:
                problems.append((f"mounts.{name}", None, "is missing (one frame per leg)"))
        for name in JOINT_NAMES:
            if name not in self.linkages:
                problems.append((f"linkages.{name}", None, "is missing (one per joint)"))
        for name in JOINT_NAMES:
            joint = getattr(self.leg, name)
            if name != "alpha" and joint.parent_frame is None:
                problems.append((f"leg.{name}.parent_frame", None, "is required"))
            span = joint.upper_limit - joint.lower_limit
            if span >= math.pi:
                problems.append(
                    (f"leg.{name}.upper_limit", joint.upper_limit, "range should be < 180°")
                )
        if problems:
            raise CrossFieldError(problems)
        return self
