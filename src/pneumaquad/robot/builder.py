"""The MuJoCo model of the robot, built from a robot parameter set (never by hand).

Bodies use SrLib's link frames (App. C.2): each link is a capsule along its body's z axis,
joints sit where the listings put them, and the coxa is the two welded capsules of the
listing in one body. Each joint is driven by its cylinder: a two-site spatial tendon
between the barrel pivot on the parent link and the rod-end pin on the child link, whose
length is the pin-to-pin distance of eq 5.2.1-5.2.6, with a ``motor`` actuator applying
the cylinder force along it (torque = force × exact moment arm, eq 5.2.7-5.2.9). The
tendon's armature is the moving piston/rod mass (or, with ``simulation.piston_inertia =
"joint"``, the hinge's armature its mean reflected inertia); its ``frictionloss`` and
``damping`` hold the seal friction when it lives in MuJoCo's constraint solver.

Configurations (thesis 5.4, 3.1.2):

``quadruped``  the whole robot free on the ground;
``fixed``      the thorax fixed in space as in the thesis's validation (all four legs
               simulated; experiments command the front-right leg);
``testbed``    the two-legged testbed: front legs only, the rear of the thorax rolling
               on passive wheels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import mujoco
import numpy as np

from pneumaquad.params import JOINT_NAMES, LEG_NAMES, ActuatorParameters, load_actuator
from pneumaquad.params.robot_schema import Frame, LinkParameters, RobotParameters

from .environment import WORLD_CONAFFINITY, WORLD_CONTYPE, add_environment
from .frames import frame_matrix, invert, rotation_to_quaternion
from .linkage import Linkage, design_linkage, moment_arm

__all__ = ["CONFIGURATIONS", "RobotModel", "build_robot", "leg_linkages", "tibia_body_legs"]

CONFIGURATIONS = ("quadruped", "fixed", "testbed")

_ROBOT_CONTYPE, _ROBOT_CONAFFINITY = WORLD_CONAFFINITY, WORLD_CONTYPE
_CYLINDER_RGBA = (0.75, 0.75, 0.78, 1.0)
#: Time constant of the joint-limit (cylinder end stop) constraint [s].
END_STOP_TIME_CONSTANT = 0.002
#: Time constant of the seal's dry-friction constraint [s].
SEAL_FRICTION_TIME_CONSTANT = 0.002


@dataclass(frozen=True)
class RobotJoints:
    """The robot's cylinder-driven joints as its parameters define them, without MuJoCo.

    What the actuators and controllers of the joints need (the network actuator side
    builds its cylinders from this alone, :func:`robot_joints`).

    Attributes
    ----------
    parameters : RobotParameters
    actuators : dict
        Joint type → its actuator parameters.
    configuration : str
    legs : tuple of str
        Legs present, in :data:`LEG_NAMES` order.
    joint_names : tuple of str
        ``"<leg>_<joint>"`` for every simulated joint, leg by leg, alpha-beta-gamma.
    joint_types : tuple of str
        ``"alpha"``, ``"beta"`` or ``"gamma"`` per simulated joint.
    linkages : dict
        Joint type → :class:`Linkage`.
    """

    parameters: RobotParameters
    actuators: dict[str, ActuatorParameters]
    configuration: str
    legs: tuple[str, ...]
    joint_names: tuple[str, ...]
    joint_types: tuple[str, ...]
    linkages: dict[str, Linkage]

    @property
    def joint_count(self) -> int:
        """Number of simulated (cylinder-driven) joints."""
        return len(self.joint_names)

    def lower_limits(self) -> np.ndarray:
        """Joint lower limits [rad], per simulated joint."""
        return np.array([getattr(self.parameters.leg, t).lower_limit for t in self.joint_types])

    def upper_limits(self) -> np.ndarray:
        """Joint upper limits [rad], per simulated joint."""
        return np.array([getattr(self.parameters.leg, t).upper_limit for t in self.joint_types])


def robot_joints(parameters: RobotParameters, configuration: str = "quadruped") -> RobotJoints:
    """The joints of ``configuration`` (one of :data:`CONFIGURATIONS`): actuator files
    loaded, linkages as given or designed from the stroke; no MuJoCo model is built."""
    if configuration not in CONFIGURATIONS:
        raise ValueError(f"configuration {configuration!r} should be one of {CONFIGURATIONS}")
    mounting = parameters.actuators
    actuators = {name: load_actuator(getattr(mounting, name), mounting.actuator_overrides())
                 for name in JOINT_NAMES}
    legs = LEG_NAMES if configuration != "testbed" else ("front_left", "front_right")
    names = tuple(f"{leg}_{joint}" for leg in legs for joint in JOINT_NAMES)
    return RobotJoints(
        parameters=parameters, actuators=actuators, configuration=configuration, legs=legs,
        joint_names=names, joint_types=tuple(n.rsplit("_", 1)[1] for n in names),
        linkages=leg_linkages(parameters, actuators))


@dataclass(frozen=True)
class RobotModel(RobotJoints):
    """A compiled robot model: its joints (:class:`RobotJoints`) and the MuJoCo model with
    the indices the simulation needs.

    Attributes
    ----------
    model : mujoco.MjModel
    environment : str
    qpos_address, dof_address, tendon_id, actuator_id, foot_site_id : ndarray of int
        Per simulated joint (feet: per leg).
    """

    model: mujoco.MjModel
    environment: str
    qpos_address: np.ndarray = field(repr=False)
    dof_address: np.ndarray = field(repr=False)
    tendon_id: np.ndarray = field(repr=False)
    actuator_id: np.ndarray = field(repr=False)
    foot_site_id: np.ndarray = field(repr=False)
    thorax_id: int = 0
    free: bool = False
    xml: str = field(default="", repr=False)

    def to_xml(self) -> str:
        """The model as MJCF text, to open in MuJoCo's own viewer."""
        return self.xml


def tibia_body_legs(robot: RobotModel) -> dict[int, int]:
    """Body id of each leg's tibia (the foot link) → index of the leg in ``robot.legs``.

    A contact is a foot contact when one of its geoms belongs to the body
    ``<leg>_tibia`` (:meth:`RobotSimulation.foot_normal_forces
    <pneumaquad.robot.simulation.RobotSimulation.foot_normal_forces>`,
    :func:`pneumaquad.robot.feedback.foot_contact_forces`).
    """
    model = robot.model
    return {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{leg}_tibia"): index
            for index, leg in enumerate(robot.legs)}


def leg_linkages(
    parameters: RobotParameters, actuators: dict[str, ActuatorParameters]
) -> dict[str, Linkage]:
    """The cylinder linkage of each joint type: as given, or designed from the stroke."""
    linkages = {}
    for name in JOINT_NAMES:
        given = parameters.linkages[name]
        joint = getattr(parameters.leg, name)
        if given.child_pivot_radius is None:
            linkages[name] = design_linkage(
                given.parent_pivot_radius,
                actuators[name].cylinder.stroke,
                joint.lower_limit,
                joint.upper_limit,
                given.direction,
            )
        else:
            linkages[name] = Linkage(
                given.parent_pivot_radius,
                given.child_pivot_radius,
                given.included_angle_at_zero,
                given.retracted_length,
                given.direction,
            )
    return linkages


def _matrix(frame: Frame) -> np.ndarray:
    return frame_matrix(frame.rotation_zyx, frame.position)


def _place(body: mujoco.MjsBody, transform: np.ndarray) -> None:
    body.pos = list(transform[:3, 3])
    body.quat = list(rotation_to_quaternion(transform[:3, :3]))


def _capsule(
    body: mujoco.MjsBody,
    name: str,
    link: LinkParameters,
    transform: np.ndarray,
    friction: float,
    contact_time_constant: float,
) -> mujoco.MjsGeom:
    radius = link.diameter / 2
    half = (link.collision_length if link.collision_length is not None else link.length) / 2
    geom = body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_CAPSULE if half > 0 else mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[radius, half, 0.0] if half > 0 else [radius, 0.0, 0.0],
        pos=list(transform[:3, 3]),
        quat=list(rotation_to_quaternion(transform[:3, :3])),
        rgba=[*link.color, 1.0],
    )
    geom.contype = _ROBOT_CONTYPE
    geom.conaffinity = _ROBOT_CONAFFINITY
    geom.friction = [friction, 0.005, 0.0001]
    geom.solref = [contact_time_constant, 1.0]
    # SrLib's UpdateInertia(density) on the listed capsule; collision_length only changes
    # the contact shape, so the mass comes from the full length.
    volume = math.pi * radius**2 * link.length + 4.0 / 3.0 * math.pi * radius**3
    geom.mass = link.mass if link.mass is not None else link.density * volume
    return geom


def _inertia_override(body: mujoco.MjsBody, link: LinkParameters, mass: float) -> None:
    if link.inertia is not None:
        body.explicitinertial = True
        body.mass = mass
        body.inertia = list(link.inertia)
        body.ipos = [0.0, 0.0, 0.0]
        body.iquat = [1.0, 0.0, 0.0, 0.0]


def _pivot_sites(
    parent: mujoco.MjsBody,
    child: mujoco.MjsBody,
    prefix: str,
    joint_in_parent: np.ndarray,
    child_in_parent: np.ndarray,
    linkage: Linkage,
    axial_offset: float,
) -> tuple[str, str]:
    """Barrel pivot on the parent, rod pin on the child, in the plane normal to the axis."""
    origin = joint_in_parent[:3, 3]
    axis = joint_in_parent[:3, 2]
    toward_parent = -origin - np.dot(-origin, axis) * axis
    if np.linalg.norm(toward_parent) < 1e-9:
        toward_parent = joint_in_parent[:3, 0]
    u = toward_parent / np.linalg.norm(toward_parent)
    v = np.cross(axis, u)
    offset = axial_offset * axis
    barrel = origin + linkage.parent_pivot_radius * u + offset
    angle = linkage.direction * linkage.included_angle_at_zero
    pin_in_parent = (
        origin + linkage.child_pivot_radius * (math.cos(angle) * u + math.sin(angle) * v) + offset
    )
    pin = invert(child_in_parent) @ np.append(pin_in_parent, 1.0)
    parent.add_site(name=f"{prefix}_barrel_pivot", pos=list(barrel), size=[0.006, 0, 0])
    child.add_site(name=f"{prefix}_rod_pin", pos=list(pin[:3]), size=[0.006, 0, 0])
    return f"{prefix}_barrel_pivot", f"{prefix}_rod_pin"


def _add_cylinder(
    spec: mujoco.MjSpec,
    prefix: str,
    sites: tuple[str, str],
    moving_mass: float,
    actuator: ActuatorParameters,
) -> None:
    """The cylinder's tendon (armature ``moving_mass`` [kg], 0 when the mass is held by
    the joint) and its force motor."""
    tendon = spec.add_tendon(name=f"{prefix}_cylinder")
    tendon.wrap_site(sites[0])
    tendon.wrap_site(sites[1])
    tendon.armature = moving_mass
    # Dry seal friction that sticks: a stiff friction constraint (time constant 2 ms, two
    # default steps, and never below MuJoCo's 2-step minimum; impedance 0.99), as
    # recommended in DESIGN.md section 4. A fixed time constant keeps the friction the same
    # physics when the step is refined.
    tendon.solref_friction = [max(SEAL_FRICTION_TIME_CONSTANT, 2.0 * spec.option.timestep), 1.0]
    tendon.solimp_friction = [0.99, 0.99, 0.001, 0.5, 2.0]
    tendon.width = 0.6 * actuator.cylinder.bore
    tendon.rgba = list(_CYLINDER_RGBA)
    motor = spec.add_actuator(name=f"{prefix}_cylinder", target=f"{prefix}_cylinder")
    motor.trntype = mujoco.mjtTrn.mjTRN_TENDON
    motor.gainprm[0] = 1.0
    motor.ctrllimited = False


def _add_leg(
    spec: mujoco.MjSpec,
    thorax: mujoco.MjsBody,
    leg: str,
    parameters: RobotParameters,
    linkages: dict[str, Linkage],
    actuators: dict[str, ActuatorParameters],
) -> None:
    p = parameters
    contact_tc = p.contact.time_constant
    mount = _matrix(p.mounts[leg])
    joint_frames = {name: getattr(p.leg, name) for name in JOINT_NAMES}
    coxa1_in_thorax = mount @ invert(_matrix(joint_frames["alpha"].child_frame))
    coxa2_in_coxa1 = _matrix(p.leg.coxa_weld_parent_frame) @ invert(
        _matrix(p.leg.coxa_weld_child_frame)
    )
    beta_in_coxa1 = coxa2_in_coxa1 @ _matrix(joint_frames["beta"].parent_frame)
    femur_in_coxa1 = beta_in_coxa1 @ invert(_matrix(joint_frames["beta"].child_frame))
    gamma_in_femur = _matrix(joint_frames["gamma"].parent_frame)
    tibia_in_femur = gamma_in_femur @ invert(_matrix(joint_frames["gamma"].child_frame))

    bodies = {}
    chain = (
        ("alpha", "coxa", thorax, coxa1_in_thorax, mount),
        ("beta", "femur", None, femur_in_coxa1, beta_in_coxa1),
        ("gamma", "tibia", None, tibia_in_femur, gamma_in_femur),
    )
    parent = thorax
    for joint_name, link_name, _, child_in_parent, joint_in_parent in chain:
        body = parent.add_body(name=f"{leg}_{link_name}")
        _place(body, child_in_parent)
        joint = joint_frames[joint_name]
        child_frame = _matrix(joint.child_frame)
        hinge = body.add_joint(
            name=f"{leg}_{joint_name}",
            type=mujoco.mjtJoint.mjJNT_HINGE,
            pos=list(child_frame[:3, 3]),
            axis=list(child_frame[:3, 2]),
            range=[joint.lower_limit, joint.upper_limit],
            limited=mujoco.mjtLimited.mjLIMITED_TRUE,
            damping=joint.damping,
        )
        # The joint limits are the cylinder's end stops: a stiff limit constraint (time
        # constant 2 ms) instead of MuJoCo's soft default, which let a cylinder pushing at
        # full pressure overrun its limit by several degrees.
        hinge.solref_limit = [max(END_STOP_TIME_CONSTANT, 2.0 * spec.option.timestep), 1.0]
        hinge.solimp_limit = [0.99, 0.999, 0.001, 0.5, 2.0]
        if link_name == "coxa":
            first = _capsule(body, f"{leg}_coxa1", p.coxa1, np.eye(4), p.contact.body_friction,
                             contact_tc)
            second = _capsule(body, f"{leg}_coxa2", p.coxa2, coxa2_in_coxa1,
                              p.contact.body_friction, contact_tc)
            _inertia_override(body, p.coxa1, first.mass + second.mass)
        else:
            link = getattr(p, link_name)
            friction = p.contact.foot_friction if link_name == "tibia" else p.contact.body_friction
            geom = _capsule(body, f"{leg}_{link_name}", link, np.eye(4), friction, contact_tc)
            _inertia_override(body, link, geom.mass)
        linkage = linkages[joint_name]
        sites = _pivot_sites(
            parent,
            body,
            f"{leg}_{joint_name}",
            joint_in_parent,
            child_in_parent,
            linkage,
            p.linkages[joint_name].axial_offset,
        )
        moving_mass = p.linkages[joint_name].moving_mass
        if p.simulation.piston_inertia == "joint":
            hinge.armature = moving_mass * _mean_squared_moment_arm(
                linkage, joint.lower_limit, joint.upper_limit)
            moving_mass = 0.0
        _add_cylinder(spec, f"{leg}_{joint_name}", sites, moving_mass, actuators[joint_name])
        bodies[link_name] = body
        parent = body
    tip = -(p.tibia.length / 2 + p.tibia.diameter / 2)
    bodies["tibia"].add_site(name=f"{leg}_foot", pos=[0.0, 0.0, tip], size=[0.01, 0, 0])


def _mean_squared_moment_arm(linkage: Linkage, lower: float, upper: float) -> float:
    """Mean of the squared moment arm r(θ)² [m²] over the joint range [lower, upper]
    [rad] (Simpson's rule on 64 intervals): with the piston mass m [kg], m·⟨r²⟩ [kg m²] is
    the joint armature of ``simulation.piston_inertia = "joint"``."""
    angles = np.linspace(lower, upper, 65)
    squared = np.asarray(moment_arm(linkage, angles)) ** 2
    weights = np.ones(65)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    return float(weights @ squared / (3.0 * 64))


def _add_testbed_wheels(spec: mujoco.MjSpec, thorax: mujoco.MjsBody, p: RobotParameters) -> None:
    """Passive wheels under the rear end of the thorax (thorax frame: x up, z forward)."""
    t = p.testbed
    rear = -p.thorax.length / 2
    for side, sign in (("left", -1.0), ("right", 1.0)):
        wheel = thorax.add_body(
            name=f"testbed_{side}_wheel",
            pos=[-t.axle_drop, sign * t.track_width / 2, rear],
        )
        wheel.add_joint(name=f"testbed_{side}_wheel", type=mujoco.mjtJoint.mjJNT_HINGE,
                        axis=[0.0, 1.0, 0.0])
        geom = wheel.add_geom(
            name=f"testbed_{side}_wheel",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[t.wheel_radius, t.wheel_width / 2, 0.0],
            quat=list(rotation_to_quaternion(frame_matrix((0, 0, math.pi / 2), (0, 0, 0))[:3, :3])),
            rgba=[0.2, 0.2, 0.2, 1.0],
        )
        geom.mass = t.wheel_mass
        geom.contype = _ROBOT_CONTYPE
        geom.conaffinity = _ROBOT_CONAFFINITY
        geom.friction = [1.0, 0.005, 0.0001]
    strut = thorax.add_geom(
        name="testbed_axle",
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        fromto=[0.0, -t.track_width / 2, rear, 0.0, t.track_width / 2, rear],
        size=[0.008, 0, 0],
        rgba=[0.3, 0.3, 0.3, 1.0],
    )
    strut.contype = 0
    strut.conaffinity = 0
    strut.mass = 0.05


def _add_visual_assets(spec: mujoco.MjSpec) -> None:
    texture = spec.add_texture(
        name="grid",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        rgb1=[0.62, 0.62, 0.58],
        rgb2=[0.52, 0.52, 0.48],
        width=256,
        height=256,
    )
    material = spec.add_material(name="grid", texrepeat=[8, 8], reflectance=0.05)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture.name
    spec.add_texture(  # a pale sky, so the view above the horizon is not a black band
        name="sky",
        type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
        rgb1=[0.78, 0.84, 0.92],
        rgb2=[0.97, 0.97, 0.97],
        width=256,
        height=256,
    )
    spec.worldbody.add_light(name="sun", pos=[0, 0, 4], dir=[0, 0.3, -1], castshadow=True)
    # the camera's own light, brighter than MuJoCo's default, so the robot reads in every frame
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.55, 0.55, 0.55]
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 960


def build_robot(
    parameters: RobotParameters,
    configuration: str = "quadruped",
    environment: str = "flat",
    seed: int = 0,
) -> RobotModel:
    """Build and compile the MuJoCo model of the robot.

    Parameters
    ----------
    parameters : RobotParameters
        From :func:`pneumaquad.params.load_robot`.
    configuration : str
        One of :data:`CONFIGURATIONS`.
    environment : str
        One of :data:`pneumaquad.robot.environment.ENVIRONMENTS`.
    seed : int
        Seed of the rough-terrain field.

    Returns
    -------
    RobotModel
    """
    joints = robot_joints(parameters, configuration)
    p = parameters
    actuators, linkages, legs, names = (joints.actuators, joints.linkages, joints.legs,
                                        joints.joint_names)
    spec = mujoco.MjSpec()
    spec.modelname = f"{p.meta.name}-{configuration}-{environment}"
    spec.option.timestep = p.simulation.control_step / p.simulation.physics_steps
    spec.option.integrator = getattr(
        mujoco.mjtIntegrator, f"mjINT_{p.simulation.integrator.upper()}"
    )
    spec.option.solver = getattr(mujoco.mjtSolver, f"mjSOL_{p.simulation.solver.upper()}")
    spec.option.iterations = p.simulation.solver_iterations
    spec.option.tolerance = p.simulation.solver_tolerance
    spec.option.noslip_iterations = p.simulation.noslip_iterations
    # Elliptic friction cones by default: with the pyramidal cone and ground friction 5 the
    # feet sank about 2 cm into the ground; elliptic cones keep it near 0.15 mm.
    spec.option.cone = getattr(mujoco.mjtCone, f"mjCONE_{p.contact.friction_cone.upper()}")
    spec.option.impratio = p.contact.friction_impedance_ratio
    # A diverging state stops the run with an error (robot.simulation) instead of
    # MuJoCo's silent reset to the initial state, which would make time jump back.
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
    if not p.simulation.constraint_islands:
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_ISLAND
    spec.compiler.degree = False
    _add_visual_assets(spec)
    add_environment(spec, environment, p.environment, p.contact, seed)

    placement = _matrix(p.placement)
    thorax = spec.worldbody.add_body(name="thorax")
    _place(thorax, placement)
    free = configuration != "fixed"
    if free:
        thorax.add_freejoint(name="thorax")
    geom = _capsule(thorax, "thorax", p.thorax, np.eye(4), p.contact.body_friction,
                    p.contact.time_constant)
    _inertia_override(thorax, p.thorax, geom.mass)
    thorax.add_camera(name="side", pos=[0.6, -2.2, 0.3], xyaxes=[1, 0, 0, 0, 0, 1],
                      mode=mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM)
    for leg in legs:
        _add_leg(spec, thorax, leg, p, linkages, actuators)
    if configuration == "testbed":
        _add_testbed_wheels(spec, thorax, p)
    model = spec.compile()
    joint_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in names]
    return RobotModel(
        **{f.name: getattr(joints, f.name) for f in fields(RobotJoints)},
        model=model,
        environment=environment,
        qpos_address=np.array([model.jnt_qposadr[i] for i in joint_ids]),
        dof_address=np.array([model.jnt_dofadr[i] for i in joint_ids]),
        tendon_id=np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, f"{n}_cylinder") for n in names]
        ),
        actuator_id=np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{n}_cylinder") for n in names]
        ),
        foot_site_id=np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{leg}_foot") for leg in legs]
        ),
        thorax_id=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "thorax"),
        free=free,
        xml=spec.to_xml(),
    )
