"""The 3-D scene of the operator console: the robot drawn from its compiled MuJoCo model.

Every geom of the model becomes one viser node named ``/robot/geoms/<geom name>``
(``/world/...`` for geoms of the world body: ground grid, obstacles), the twelve
cylinders are line segments between their tendon sites (``<joint>_barrel_pivot`` →
``<joint>_rod_pin``) and contacts are points with force arrows from
:func:`mujoco.mj_contactForce`. :meth:`RobotScene.update` copies the poses of the
current :class:`mujoco.MjData` into the scene; the console calls it after every chunk.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np
import viser

from pneumaquad.robot.builder import RobotModel

if TYPE_CHECKING:
    from pneumaquad.robot.feedback import FootFeedback
    from pneumaquad.robot.simulation import RobotSimulation

    from .replay import ReplayRun, Stability

__all__ = ["FeedbackArrows", "RobotScene", "StabilityOverlay", "capsule_mesh",
           "cylinder_mesh", "geom_node_name"]

#: Length of a contact-force arrow per newton [m/N].
FORCE_ARROW_SCALE = 0.004
_CYLINDER_COLOUR = (190, 190, 200)
_CONTACT_COLOUR = (255, 60, 40)
_FORCE_COLOUR = (255, 170, 0)
_FEEDBACK_COLOUR = (200, 40, 255)
_GROUND_SIZE = 6.0
_POLYGON_COLOUR = (40, 120, 255)
_COM_STABLE_COLOUR = (40, 200, 80)
_COM_UNSTABLE_COLOUR = (230, 30, 30)
_COM_UNKNOWN_COLOUR = (150, 150, 150)
#: Height of the support polygon and COM marker above the stance feet' mean height [m].
_OVERLAY_LIFT = 0.002


def _lathe(profile_radius: np.ndarray, profile_height: np.ndarray,
           segments: int) -> tuple[np.ndarray, np.ndarray]:
    """Surface of revolution about z of a closed profile (first and last radius 0)."""
    angles = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    rings = len(profile_radius)
    vertices = np.empty((rings * segments, 3))
    vertices[:, 0] = (profile_radius[:, None] * np.cos(angles)[None, :]).ravel()
    vertices[:, 1] = (profile_radius[:, None] * np.sin(angles)[None, :]).ravel()
    vertices[:, 2] = np.repeat(profile_height, segments)
    faces = []
    for ring in range(rings - 1):
        for k in range(segments):
            a = ring * segments + k
            b = ring * segments + (k + 1) % segments
            c = a + segments
            d = b + segments
            faces.append((a, b, d))
            faces.append((a, d, c))
    return vertices.astype(np.float32), np.array(faces, dtype=np.uint32)


def capsule_mesh(radius: float, half_length: float,
                 segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a capsule along z (MuJoCo's capsule: radius, half length)."""
    polar = np.linspace(0.0, 0.5 * np.pi, segments // 2 + 1)
    bottom_radius = radius * np.sin(polar)
    bottom_height = -half_length - radius * np.cos(polar)
    profile_radius = np.concatenate([bottom_radius, bottom_radius[::-1]])
    profile_height = np.concatenate([bottom_height, -bottom_height[::-1]])
    return _lathe(profile_radius, profile_height, segments)


def cylinder_mesh(radius: float, half_length: float,
                  segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a closed cylinder along z."""
    profile_radius = np.array([0.0, radius, radius, 0.0])
    profile_height = np.array([-half_length, -half_length, half_length, half_length])
    return _lathe(profile_radius, profile_height, segments)


def geom_node_name(model: mujoco.MjModel, geom: int, root: str = "") -> str:
    """Scene node name of ``geom``: ``/world/<name>`` (static) or ``/robot/geoms/<name>``.

    ``root`` is prepended (``"/replay"`` for the replayed robot).
    """
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, geom) or f"geom{geom}"
    prefix = "/world" if model.geom_bodyid[geom] == 0 else "/robot/geoms"
    return f"{root}{prefix}/{name}"


def _geom_colour(model: mujoco.MjModel, geom: int) -> tuple[int, int, int]:
    material = model.geom_matid[geom]
    rgba = model.mat_rgba[material] if material >= 0 else model.geom_rgba[geom]
    return tuple(round(255 * float(c)) for c in rgba[:3])  # type: ignore[return-value]


def _quaternion(matrix: np.ndarray) -> np.ndarray:
    quaternion = np.empty(4)
    mujoco.mju_mat2Quat(quaternion, np.ascontiguousarray(matrix, dtype=np.float64))
    return quaternion


class RobotScene:
    """The robot, its cylinders, the environment and contacts in a viser scene.

    Parameters
    ----------
    server : viser.ViserServer
    robot : RobotModel or ReplayRun
        The compiled robot (anything with ``model``, ``joint_names``); its geoms and
        tendon sites are drawn.
    root : str
        Prefix of every node name (``"/replay"`` for a replayed run, so that it does not
        replace the live robot's nodes).
    """

    def __init__(self, server: viser.ViserServer, robot: RobotModel | ReplayRun,
                 root: str = "") -> None:
        self.server = server
        self.robot = robot
        self.root = root
        model = robot.model
        self.geom_nodes: dict[int, viser.SceneNodeHandle] = {}
        self.dynamic_geoms: list[int] = []
        for geom in range(model.ngeom):
            node = self._add_geom(geom)
            if node is None:
                continue
            self.geom_nodes[geom] = node
            if model.geom_bodyid[geom] != 0:
                self.dynamic_geoms.append(geom)
        self.cylinder_sites = np.array([
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"{joint}_{end}")
             for end in ("barrel_pivot", "rod_pin")]
            for joint in robot.joint_names
        ]).reshape(-1, 2)
        self.cylinder_sites = self.cylinder_sites[np.all(self.cylinder_sites >= 0, axis=1)]
        self.cylinders = server.scene.add_line_segments(
            f"{root}/robot/cylinders", np.zeros((len(self.cylinder_sites), 2, 3)),
            _CYLINDER_COLOUR,
            thickness=0.012,
        )
        self.contact_points = server.scene.add_point_cloud(
            f"{root}/contacts/points", np.zeros((1, 3)), np.array([_CONTACT_COLOUR]),
            point_size=0.02, point_shape="circle", visible=False,
        )
        self.contact_forces = server.scene.add_line_segments(
            f"{root}/contacts/forces", np.zeros((1, 2, 3)), _FORCE_COLOUR, thickness=0.006,
            visible=False,
        )
        self.contact_count = 0

    def _add_geom(self, geom: int) -> viser.SceneNodeHandle | None:
        model, scene = self.robot.model, self.server.scene
        name = geom_node_name(model, geom, self.root)
        size = model.geom_size[geom]
        colour = _geom_colour(model, geom)
        kind = model.geom_type[geom]
        placement = {"position": model.geom_pos[geom], "wxyz": model.geom_quat[geom]}
        if kind == mujoco.mjtGeom.mjGEOM_PLANE:
            width = 2.0 * size[0] if size[0] > 0 else _GROUND_SIZE
            height = 2.0 * size[1] if size[1] > 0 else _GROUND_SIZE
            return scene.add_grid(name, width=width, height=height, cell_size=0.1,
                                  section_size=1.0, plane_color=colour, plane_opacity=0.6,
                                  **placement)
        if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
            return scene.add_icosphere(name, radius=float(size[0]), color=colour,
                                       subdivisions=2, **placement)
        if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            return scene.add_icosphere(name, radius=1.0, color=colour, subdivisions=2,
                                       scale=tuple(float(s) for s in size), **placement)
        if kind == mujoco.mjtGeom.mjGEOM_BOX:
            return scene.add_box(name, color=colour, dimensions=2.0 * size, **placement)
        if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            vertices, faces = capsule_mesh(float(size[0]), float(size[1]))
        elif kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
            vertices, faces = cylinder_mesh(float(size[0]), float(size[1]))
        else:
            return None  # meshes and height fields are not used by the robot models
        return scene.add_mesh_simple(name, vertices, faces, color=colour, **placement)

    def update(self, data: mujoco.MjData, show_contacts: bool = True) -> None:
        """Copy geom poses, cylinder end points and contacts from ``data`` into the scene."""
        model = self.robot.model
        with self.server.atomic():
            for geom in self.dynamic_geoms:
                node = self.geom_nodes[geom]
                node.position = data.geom_xpos[geom].copy()
                node.wxyz = _quaternion(data.geom_xmat[geom])
            self.cylinders.points = data.site_xpos[self.cylinder_sites].copy()
            points, arrows = self.contacts(model, data) if show_contacts else (None, None)
            if points is None or len(points) == 0:
                self.contact_points.visible = False
                self.contact_forces.visible = False
                self.contact_count = 0
            else:
                self.contact_points.points = points.astype(np.float32)
                self.contact_points.colors = np.tile(
                    np.array(_CONTACT_COLOUR, dtype=np.uint8), (len(points), 1))
                self.contact_forces.points = arrows.astype(np.float32)
                self.contact_forces.colors = np.tile(
                    np.array(_FORCE_COLOUR, dtype=np.uint8), (len(points), 2, 1))
                self.contact_points.visible = True
                self.contact_forces.visible = True
                self.contact_count = len(points)

    @staticmethod
    def contacts(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Contact positions (n, 3) [m] and force arrows (n, 2, 3) [m] in world coordinates.

        The arrow starts at the contact and points along the contact force on the second
        geom (normal from the first to the second), :data:`FORCE_ARROW_SCALE` m per N.
        """
        count = data.ncon
        points = np.empty((count, 3))
        arrows = np.empty((count, 2, 3))
        wrench = np.zeros(6)
        for index in range(count):
            contact = data.contact[index]
            mujoco.mj_contactForce(model, data, index, wrench)
            force = contact.frame.reshape(3, 3).T @ wrench[:3]
            points[index] = contact.pos
            arrows[index, 0] = contact.pos
            arrows[index, 1] = contact.pos + FORCE_ARROW_SCALE * force
        return points, arrows

    def set_visible(self, visible: bool) -> None:
        """Show or hide the whole robot and its environment (contacts: hidden only)."""
        with self.server.atomic():
            for node in self.geom_nodes.values():
                node.visible = visible
            self.cylinders.visible = visible
            if not visible:
                self.contact_points.visible = False
                self.contact_forces.visible = False

    def remove(self) -> None:
        """Remove every node of this robot from the scene (before a rebuild)."""
        for node in self.geom_nodes.values():
            node.remove()
        for node in (self.cylinders, self.contact_points, self.contact_forces):
            node.remove()
        self.geom_nodes.clear()
        self.dynamic_geoms.clear()


class StabilityOverlay:
    """Support polygon (blue line segments) and centre-of-mass projection (sphere).

    The marker is green inside the polygon, red when the stability margin is negative,
    grey when it is unknown (no foot in contact); both are drawn just above the mean
    height of the stance feet.
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self.polygon = server.scene.add_line_segments(
            "/stability/support_polygon", np.zeros((1, 2, 3)), _POLYGON_COLOUR,
            thickness=0.008, visible=False,
        )
        self.com = server.scene.add_icosphere(
            "/stability/centre_of_mass", radius=0.015, color=_COM_UNKNOWN_COLOUR,
            subdivisions=2, visible=False,
        )

    def update(self, stability: Stability) -> None:
        """Draw ``stability`` (see :class:`.replay.Stability`)."""
        height = stability.height + _OVERLAY_LIFT
        vertices = np.asarray(stability.polygon, dtype=float)
        with self.server.atomic():
            if len(vertices) >= 2:
                ends = np.roll(vertices, -1, axis=0) if len(vertices) > 2 else vertices[::-1]
                count = len(vertices) if len(vertices) > 2 else 1
                segments = np.empty((count, 2, 3))
                segments[:, 0, :2] = vertices[:count]
                segments[:, 1, :2] = ends[:count]
                segments[:, :, 2] = height
                self.polygon.points = segments.astype(np.float32)
                self.polygon.colors = np.tile(np.array(_POLYGON_COLOUR, dtype=np.uint8),
                                              (count, 2, 1))
                self.polygon.visible = True
            else:
                self.polygon.visible = False
            if np.all(np.isfinite(stability.com)):
                self.com.position = (float(stability.com[0]), float(stability.com[1]), height)
                self.com.color = self.colour(stability.margin)
                self.com.visible = True
            else:
                self.com.visible = False

    @staticmethod
    def colour(margin: float) -> tuple[int, int, int]:
        """Marker colour for ``margin`` [m]: green ≥ 0, red < 0, grey unknown."""
        if not np.isfinite(margin):
            return _COM_UNKNOWN_COLOUR
        return _COM_UNSTABLE_COLOUR if margin < 0.0 else _COM_STABLE_COLOUR


class FeedbackArrows:
    """Total feedback force (contact + actuator resistance) of each commanded foot.

    A magenta line segment from the foot site along the force,
    :data:`FORCE_ARROW_SCALE` m per N (see :mod:`pneumaquad.robot.feedback`).
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self.segments = server.scene.add_line_segments(
            "/feedback/forces", np.zeros((1, 2, 3)), _FEEDBACK_COLOUR, thickness=0.01,
            visible=False,
        )

    def update(self, simulation: RobotSimulation, feedback: FootFeedback,
               legs: list[str]) -> None:
        """Draw the total feedback force of ``legs`` from their foot positions."""
        if not legs:
            self.hide()
            return
        indices = [feedback.legs.index(leg) for leg in legs]
        feet = simulation.foot_positions()[indices]
        arrows = np.stack([feet, feet + FORCE_ARROW_SCALE * feedback.total[indices]], axis=1)
        with self.server.atomic():
            self.segments.points = arrows.astype(np.float32)
            self.segments.colors = np.tile(np.array(_FEEDBACK_COLOUR, dtype=np.uint8),
                                           (len(legs), 2, 1))
            self.segments.visible = True

    def hide(self) -> None:
        """Hide the arrows (replay mode)."""
        self.segments.visible = False
