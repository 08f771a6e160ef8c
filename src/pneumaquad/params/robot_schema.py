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

from .fields import (
    MAX_LENGTH,
    MAX_MASS,
    MAX_TIME_CONSTANT,
    AbsolutePressure,
    Bounds,
    ControlStep,
    CrossFieldError,
    Damping,
    Length,
    Mass,
    NonNegativeLength,
    NonNegativeMass,
    Number,
    ParameterModel,
    PositiveLength,
    QuantityField,
    StepCount,
    Time,
    described,
)
from .schema import ControllerParameters, Meta

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


class Frame(ParameterModel):
    """A rigid transform as SrLib writes it: ``EulerZYX(Vec3(a, b, c), Vec3(x, y, z))``.

    ``rotation_zyx`` = (a, b, c) [rad] gives R = Rz(a)·Ry(b)·Rx(c); ``position`` [m].
    """

    rotation_zyx: tuple[Angle, Angle, Angle] = described(
        "Rotation as SrLib's `EulerZYX` angles (a, b, c): R = Rz(a)·Ry(b)·Rx(c).",
        "App. C.2 listings (`EulerZYX(Vec3(a, b, c), ...)`)")
    position: tuple[Coordinate, Coordinate, Coordinate] = described(
        "Translation (x, y, z) after the rotation.",
        "App. C.2 listings (`EulerZYX(..., Vec3(x, y, z))`)")


class LinkParameters(ParameterModel):
    """A capsule link (SrLib ``SetDimension(diameter, length)``, ``UpdateInertia(density)``).

    ``length`` is the cylindrical part along the link's z axis; the hemispherical caps
    add ``diameter/2`` at each end. ``mass`` and ``inertia`` (principal moments about the
    link frame axes [kg m^2]) override the density estimate (thesis 5.6.1, 6.6.2).
    """

    diameter: PositiveLength = described(
        "Capsule diameter (SrLib `SetDimension`).",
        "App. C.2.1 (legs), C.2.2 l.24 (thorax)")
    length: NonNegativeLength = described(
        "Length of the capsule's cylindrical part along the link's z axis; the hemispherical "
        "caps add `diameter/2` at each end.",
        "App. C.2.1 (legs), C.2.2 l.24 (thorax)")
    density: Density = described(
        "Density for the mass and inertia estimate (SrLib `UpdateInertia`).",
        "App. C.2.1 (legs), C.2.2 l.26 (thorax)")
    collision_length: NonNegativeLength | None = described(
        "Cylindrical length of the collision capsule when it differs from `length`.",
        "App. C.2.2 l.28 (thorax)",
        default=None)
    mass: Annotated[Mass, Bounds(0.0, MAX_MASS, "kg")] | None = described(
        "Mass in place of the density estimate.",
        "not in thesis: better masses are thesis future work (5.6.1, 6.6.2); the thorax's is "
        "chosen so that the robot can stand (docs/robot.md)",
        default=None)
    inertia: tuple[Inertia, Inertia, Inertia] | None = described(
        "Principal moments of inertia about the link frame's axes, in place of the density "
        "estimate.",
        "not in thesis: better inertias are thesis future work (5.6.1, 6.6.2)",
        default=None)
    color: tuple[ColourComponent, ColourComponent, ColourComponent] = described(
        "Display colour (red, green, blue).",
        "App. C.2.1, C.2.2 (SrLib colours)",
        default=(0.7, 0.7, 0.7))


class JointParameters(ParameterModel):
    """A revolute joint: its frame in the parent and in the child link, limits [rad]."""

    parent_frame: Frame | None = described(
        "The joint's frame in the parent link; alpha's is the leg's mounting (`[mounts]`), the "
        "others need one.",
        "App. C.2.1 l.66, l.74",
        default=None)
    child_frame: Frame = described(
        "The joint's frame in the child link; its z axis is the rotation axis.",
        "App. C.2.1 l.54, l.67, l.75")
    lower_limit: JointAngle = described(
        "Lower joint limit.",
        "App. C.2.1 l.52, l.63, l.71; eq 5.2.2, 5.2.4, 5.2.6")
    upper_limit: JointAngle = described(
        "Upper joint limit; above `lower_limit`, less than 180° from it.",
        "App. C.2.1 l.52, l.63, l.71")
    damping: Damping = described(
        "Viscous damping of the hinge.",
        "not in thesis: the joint damping term thesis 5.6.1 suggests (0 shipped: the cylinders' "
        "friction acts instead)",
        default=0.0)

    @_model_validator(mode="after")
    def _limits(self) -> JointParameters:
        if not self.lower_limit < self.upper_limit:
            raise CrossFieldError(
                [("upper_limit", self.upper_limit, "should be above lower_limit")]
            )
        return self


class LegParameters(ParameterModel):
    """Link frames of one leg (App. C.2.1): coxa (two capsules welded), femur, tibia."""

    coxa_weld_parent_frame: Frame = described(
        "Frame welding the coxa's second capsule to its first: in the first.",
        "App. C.2.1 l.58")
    coxa_weld_child_frame: Frame = described(
        "The same weld, in the second capsule.",
        "App. C.2.1 l.59")
    alpha: JointParameters = described(
        "Alpha joint: thorax to coxa.",
        "App. C.2.1; thesis 3.1 (Table 1)")
    beta: JointParameters = described(
        "Beta joint: coxa to femur.",
        "App. C.2.1; thesis 3.1 (Table 1)")
    gamma: JointParameters = described(
        "Gamma joint: femur to tibia.",
        "App. C.2.1; thesis 3.1 (Table 1)")


class LinkageParameters(ParameterModel):
    """Cylinder between two pivots of a joint (thesis Fig. 34–36, eq 5.2.1–5.2.6).

    The barrel pivot sits on the parent link at ``parent_pivot_radius`` (l3) from the joint
    axis, the rod-end pin on the child link at ``child_pivot_radius`` (l1); ``included
    angle`` γ between the two at the axis is ``included_angle_at_zero + direction·θ``;
    the pin-to-pin length is l2 + x with ``retracted_length`` = l2. When only the parent
    radius is given, the other three are designed so that the stroke spans the joint's
    range exactly with γ centred on 90° (:func:`pneumaquad.robot.linkage.design_linkage`).
    """

    parent_pivot_radius: PositiveLength = described(
        "Distance l3 of the barrel pivot from the joint axis, on the parent link.",
        "eq 5.2.1–5.2.6 (Fig. 34–36); not in thesis: the lengths are not printed, ours are "
        "chosen (docs/robot.md)")
    child_pivot_radius: PositiveLength | None = described(
        "Distance l1 of the rod-end pin from the joint axis, on the child link; given with "
        "`included_angle_at_zero` and `retracted_length` (a measured linkage), or all three "
        "left out to be designed from the stroke and the joint range.",
        "eq 5.2.1–5.2.6; not in thesis: designed by default",
        default=None)
    included_angle_at_zero: Angle | None = described(
        "Angle γ between the two pivot arms at the axis at zero joint angle; γ = "
        "`included_angle_at_zero` + `direction`·θ.",
        "eq 5.2.2, 5.2.4, 5.2.6; not in thesis: designed by default",
        default=None)
    retracted_length: PositiveLength | None = described(
        "Pin-to-pin length l2 with the piston retracted; the length is l2 + x.",
        "eq 5.2.1–5.2.6; not in thesis: designed by default",
        default=None)
    direction: Literal[1, -1] = described(
        "Sign of the joint angle in the included angle: 1 or -1.",
        "eq 5.2.2, 5.2.4, 5.2.6")
    axial_offset: Coordinate = described(
        "Offset of the cylinder along the joint axis (for the looks only).",
        "not in thesis",
        default=0.0)
    moving_mass: NonNegativeMass = described(
        "Moving mass of piston and rod.",
        "not in thesis: a 3/8 in steel rod and piston for the stroke")

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


class CylinderMounting(ParameterModel):
    """Which actuator parameter set drives each joint type, and the robot's shared supply.

    ``supply_pressure`` [Pa absolute], when given, is the regulated supply of every
    cylinder (the robot's one regulator) in place of each actuator file's
    ``supply.supply_pressure``; e.g. ``--set 'actuators.supply_pressure="45 psig"'``.
    """

    alpha: str = described(
        "Actuator parameter set (a shipped name or a path) of the alpha joints.",
        "App. C.1.1 (alpha's 3.75 in stroke: thesis 5.5.2.3)")
    beta: str = described(
        "Actuator parameter set of the beta joints.",
        "App. C.1.1")
    gamma: str = described(
        "Actuator parameter set of the gamma joints.",
        "App. C.1.1")
    supply_pressure: AbsolutePressure | None = described(
        "Regulated supply of all twelve cylinders in place of each actuator file's "
        "`supply.supply_pressure`; gauge units refer to the gamma file's atmosphere.",
        "not in thesis: one regulator for the robot",
        default=None)
    bore: PositiveLength | None = described(
        "Bore of all twelve cylinders in place of each actuator file's `cylinder.bore` "
        "(sizing; the rod, stroke and linkage stay).",
        "not in thesis: cylinder sizing (the robot's: 1.0625 in, App. C.1.1)",
        default=None)
    valve_area_scale: Annotated[Number, Bounds(0.0, 100.0, upper_inclusive=True)] | None = (
        described(
            "Factor on the orifice areas of all twelve valves in place of each actuator "
            "file's `valve.area_scale` (sizing: a larger or smaller valve of the same "
            "characteristic).",
            "not in thesis: valve sizing",
            default=None))

    def actuator_overrides(self) -> list[str]:
        """``--set`` items that load the actuator files with this robot's supply, bore
        and valve size (those given)."""
        overrides = []
        if self.supply_pressure is not None:
            overrides.append(f'supply.supply_pressure="{self.supply_pressure!r} Pa"')
        if self.bore is not None:
            overrides.append(f'cylinder.bore="{self.bore!r} m"')
        if self.valve_area_scale is not None:
            overrides.append(f"valve.area_scale={self.valve_area_scale!r}")
        return overrides


class JointControllerParameters(ControllerParameters):
    """PID on piston position (the robot's linear potentiometers, thesis 5.2) + extras.

    ``gain_scale`` multiplies Kp, Ki and Kd (the thesis's alpha gain −25 %, 5.5.2.4);
    ``force_feedback_gain`` [V/N] feeds back the net pneumatic force's deviation from its
    low-pass mean (time constant ``force_feedback_time_constant``), adding damping from
    the pressure sensors without a steady-state error.
    """

    gain_scale: GainScale = described(
        "Factor on Kp, Ki and Kd (0.75: the thesis's alpha gain reduced by 25 %).",
        "thesis 5.5.2.4",
        default=1.0)
    force_feedback_gain: Annotated[
        float, QuantityField("voltage_per_force"), Bounds(0.0, 1.0, "V/N", lower_inclusive=True)
    ] = described(
        "Gain on the net pneumatic force's deviation from its low-pass mean: damping from the "
        "pressure sensors without a steady-state error; 0 turns it off.",
        "not in thesis: the thesis's PID has no pressure feedback (0)",
        default=0.0)
    force_feedback_time_constant: Annotated[
        Time, Bounds(0.0, MAX_TIME_CONSTANT, "s")
    ] = described(
        "Time constant of the low-pass mean of the force feedback.",
        "not in thesis",
        default=0.05)


class RobotControllerParameters(ParameterModel):
    """Joint controllers per joint type, and stance/swing gain scales for scheduling."""

    alpha: JointControllerParameters = described(
        "Controller of the alpha joints.",
        "thesis 5.5.2.3; not in thesis: gains not printed (our tuning, docs/robot.md)")
    beta: JointControllerParameters = described(
        "Controller of the beta joints.",
        "thesis 5.5.2.2; not in thesis: gains not printed (our tuning)")
    gamma: JointControllerParameters = described(
        "Controller of the gamma joints.",
        "thesis 5.5.2.1; not in thesis: gains not printed (our tuning)")
    stance_gain_scale: GainScale = described(
        "Gain factor of the joints of a leg whose foot is in contact (gain scheduling).",
        "not in thesis",
        default=1.0)
    swing_gain_scale: GainScale = described(
        "Gain factor of the joints of a swinging leg.",
        "not in thesis",
        default=1.0)


class ContactParameters(ParameterModel):
    """Friction coefficients (SrLib ``SetFriction``, App. C.2) and MuJoCo contact softness."""

    ground_friction: FrictionCoefficient = described(
        "Friction coefficient of the ground (MuJoCo takes the larger of a contact pair's).",
        "App. C.2.4 User_Modeling l.7 gives 5.0; not in thesis: 0.8 shipped, as 5 locks the "
        "feet (docs/robot.md)")
    foot_friction: FrictionCoefficient = described(
        "Friction coefficient of the feet (the tibiae).",
        "App. C.2.1 l.43 gives 3.0; not in thesis: 0.8 shipped")
    body_friction: FrictionCoefficient = described(
        "Friction coefficient of the thorax and the upper links.",
        "not in thesis",
        default=1.0)
    time_constant: Annotated[Time, Bounds(0.0, 1.0, "s")] = described(
        "Contact softness: MuJoCo `solref` time constant.",
        "not in thesis: MuJoCo contact model",
        default=0.005)
    damping_ratio: Annotated[Number, Bounds(0.0, 100.0)] = described(
        "Contact softness: MuJoCo `solref` damping ratio.",
        "not in thesis: MuJoCo contact model",
        default=1.0)
    friction_impedance_ratio: Annotated[
        Number, Bounds(1.0, 1000.0, lower_inclusive=True)
    ] = described(
        "MuJoCo `impratio`: impedance of the friction rows relative to the normal ones "
        "(elliptic cones); above 1 a loaded contact creeps less under tangential force.",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default=1.0)
    friction_cone: Literal["elliptic", "pyramidal"] = described(
        "MuJoCo `cone`: the friction cone of every contact, `elliptic` (one row per friction "
        "direction, the exact Coulomb cone) or `pyramidal` (MuJoCo's default: two rows per "
        "direction, a polygonal approximation of the cone).",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default="elliptic")


class EnvironmentParameters(ParameterModel):
    """Obstacles: block, ramp (App. C.2.3: 1.2 × 1.2 × 0.019 m), rough-terrain field."""

    block_size: tuple[EnvironmentLength, EnvironmentLength, EnvironmentLength] = described(
        "Block obstacle: its size (x, y, z).",
        "not in thesis (Fig. 4 shows a block)")
    block_position: tuple[
        EnvironmentCoordinate, EnvironmentCoordinate, EnvironmentCoordinate
    ] = described(
        "Block obstacle: its position.",
        "not in thesis")
    ramp_size: tuple[EnvironmentLength, EnvironmentLength, EnvironmentLength] = described(
        "Ramp plate: its size (x, y, z).",
        "App. C.2.3 l.4")
    ramp_position: tuple[
        EnvironmentCoordinate, EnvironmentCoordinate, EnvironmentCoordinate
    ] = described(
        "Ramp plate: position of its lower edge.",
        "not in thesis")
    ramp_slope: Annotated[
        float,
        QuantityField("angle"),
        Bounds(-math.pi / 3, math.pi / 3, "rad", lower_inclusive=True,
               lower_text="-π/3 rad (-60°)", upper_text="π/3 rad (60°)"),
    ] = described(
        "Ramp plate: its slope, up in +x.",
        "not in thesis: the listing's plate is flat")
    hill_top_length: PositiveLength = described(
        "Hill: length of its flat top, between the ramp and its mirror image down.",
        "not in thesis",
        default=0.8)
    rough_size: tuple[EnvironmentLength, EnvironmentLength] = described(
        "Rough-terrain field: its size (x, y).",
        "not in thesis")
    rough_position: tuple[EnvironmentCoordinate, EnvironmentCoordinate] = described(
        "Rough-terrain field: its position (x, y).",
        "App. C.2.4 l.11 (1 m ahead)")
    rough_max_height: PositiveLength = described(
        "Rough-terrain field: height of a raised cell.",
        "not in thesis")
    rough_cell: PositiveLength = described(
        "Rough-terrain field: cell size.",
        "not in thesis")
    rough_fill: Annotated[Number, Bounds(0.0, 1.0, lower_inclusive=True)] = described(
        "Rough-terrain field: fraction of cells raised.",
        "App. C.2.4 l.11 (\"HALF RANDOM\")",
        default=0.5)


class TestbedParameters(ParameterModel):
    """Two-legged testbed (thesis 3.1.2): the rear of the body rolls on passive wheels.

    Two wheels on one axle under the rear end of the thorax, free to spin; the axle hangs
    ``axle_drop`` below the thorax axis.
    """

    wheel_radius: PositiveLength = described(
        "Radius of the rear wheels.",
        "thesis 3.1.2 (training wheels); not in thesis: sizes")
    wheel_width: PositiveLength = described(
        "Width of a rear wheel.",
        "thesis 3.1.2; not in thesis: sizes")
    wheel_mass: Annotated[Mass, Bounds(0.0, MAX_MASS, "kg")] = described(
        "Mass of a rear wheel.",
        "thesis 3.1.2; not in thesis: sizes")
    axle_drop: NonNegativeLength = described(
        "Distance of the axle below the thorax axis.",
        "thesis 3.1.2; not in thesis: sizes")
    track_width: PositiveLength = described(
        "Distance between the two wheels.",
        "thesis 3.1.2; not in thesis: sizes")


class RobotSimulationParameters(ParameterModel):
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

    control_step: ControlStep = described(
        "Period of the controllers and the pneumatic kernel.",
        "thesis 5.5.4 (1000 Hz)")
    substeps: StepCount = described(
        "Heun steps of the pneumatic kernel per control step.",
        "not in thesis (docs/robot.md)")
    physics_steps: StepCount = described(
        "MuJoCo steps per control step.",
        "not in thesis",
        default=1)
    integrator: Literal["implicitfast", "implicit", "euler", "rk4"] = described(
        "MuJoCo `integrator`.",
        "not in thesis: MuJoCo option (`implicitfast` is MuJoCo's recommended one)",
        default="implicitfast")
    seal_friction: Literal["mujoco", "actuator"] = described(
        "Where cylinder friction lives: `mujoco`, dry friction in the constraint solver (tendon "
        "`frictionloss`, Stribeck breakaway updated each step), or `actuator`, the actuator "
        "file's force law on the motor.",
        "not in thesis: friction in the dynamics engine, as thesis 5.6.1 suggests",
        default="mujoco")
    noslip_iterations: Annotated[StrictInt, Bounds(0, 1000, lower_inclusive=True)] = described(
        "MuJoCo `noslip_iterations`: no-slip post-processing of the friction rows (0: off).",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default=0)
    solver: Literal["newton", "cg", "pgs"] = described(
        "MuJoCo `solver`: `newton`, conjugate gradient (`cg`) or projected Gauss-Seidel "
        "(`pgs`).",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default="newton")
    solver_iterations: Annotated[StrictInt, Bounds(1, 10000, lower_inclusive=True)] = described(
        "MuJoCo `iterations`: the most solver iterations per step.",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default=50)
    solver_tolerance: Annotated[Number, Bounds(0.0, 1.0, lower_inclusive=True)] = described(
        "MuJoCo `tolerance`: the solver stops once its relative cost improvement is below it "
        "(0: every iteration runs).",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default=1e-8)
    constraint_islands: StrictBool = described(
        "MuJoCo's island discovery: the constraint rows split into independent groups solved "
        "one by one (false sets the `island` disable flag).",
        "not in thesis: MuJoCo option (docs/benchmarks.md)",
        default=True)
    piston_inertia: Literal["tendon", "joint"] = described(
        "Where each cylinder's moving mass m lives: `tendon`, the tendon's armature (m·ẋ², "
        "exact), or `joint`, the hinge's armature m·⟨r²⟩ with ⟨r²⟩ the mean squared moment arm "
        "over the joint range (constant, cheaper).",
        "not in thesis: the cylinders modelled as parts of the linkage, as thesis 6.6.2 "
        "suggests",
        default="tendon")
    recording_every: Annotated[
        StrictInt, Bounds(1, 1_000_000, lower_inclusive=True)
    ] = described(
        "Control steps per recorded row.",
        "not in thesis",
        default=10)


class RobotParameters(ParameterModel):
    """A complete robot parameter set (see module docstring)."""

    meta: Meta = described(
        "Identification of the set.",
        "not in thesis: bookkeeping")
    actuators: CylinderMounting = described(
        "Which actuator file drives each joint type, and the robot's shared supply.",
        "App. C.1.1")
    thorax: LinkParameters = described(
        "The body.",
        "App. C.2.2 l.24–28")
    coxa1: LinkParameters = described(
        "First capsule of the coxa (the hip, moved by alpha).",
        "App. C.2.1 l.3–8")
    coxa2: LinkParameters = described(
        "Second capsule of the coxa, welded to the first.",
        "App. C.2.1 l.16–18")
    femur: LinkParameters = described(
        "The femur (moved by beta).",
        "App. C.2.1 l.26–30")
    tibia: LinkParameters = described(
        "The tibia, whose end is the foot (moved by gamma).",
        "App. C.2.1 l.38–43")
    leg: LegParameters = described(
        "Joint frames and limits of a leg (the same for all four).",
        "App. C.2.1")
    mounts: dict[Literal[LEG_NAMES], Frame] = described(  # type: ignore[valid-type]
        "The alpha joint's frame on the thorax, per leg (SrLib L1, R1, L2, R2).",
        "App. C.2.2 l.5–20")
    placement: Frame = described(
        "The thorax's frame in the world at the start.",
        "App. C.2.4 User_Modeling l.10")
    linkages: dict[Literal[JOINT_NAMES], LinkageParameters] = described(  # type: ignore[valid-type]
        "Cylinder linkage per joint type.",
        "thesis 5.2 (Fig. 34–36)")
    contact: ContactParameters = described(
        "Friction and contact softness.",
        "App. C.2 (`SetFriction`)")
    environment: EnvironmentParameters = described(
        "Obstacles of the environments.",
        "App. C.2.3, C.2.4")
    controller: RobotControllerParameters = described(
        "Joint controllers.",
        "thesis 5.5.2")
    simulation: RobotSimulationParameters = described(
        "Coupled-simulation settings.",
        "thesis 5.5.4")
    testbed: TestbedParameters = described(
        "The two-legged testbed's rear wheels.",
        "thesis 3.1.2")

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
