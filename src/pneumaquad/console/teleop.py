"""Teleoperation of the front feet: stylus gizmos mapped by offset and scale, through IK.

Thesis 3.3: the end effectors of the two haptic styluses are "mapped to the end effectors
of the robot via an offset and a scaling, and then converted to joint angle motions using
inverse kinematics". Here each stylus is a viser transform gizmo; its displacement ``s``
from the workspace origin, in the thorax frame, gives the foot target

    target = offset + scale · s          (thorax frame, metres)

where ``offset`` is the leg's home foot position (the reset pose) plus an operator shift.
The target goes through :func:`pneumaquad.robot.legs.solve_leg` with ``clamp=True``;
a target outside the workspace or the joint limits is clamped to the nearest reachable
foot position and flagged (its marker turns red).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np
import viser

from pneumaquad.robot.kinematics import DHTable
from pneumaquad.robot.leg_ik import IKResult
from pneumaquad.robot.legs import leg_dh_table, solve_leg, thorax_frame_points
from pneumaquad.robot.simulation import RobotSimulation

__all__ = ["FRONT_LEGS", "FootTeleoperation", "LegTarget", "map_stylus"]

FRONT_LEGS = ("front_left", "front_right")
REACHABLE_COLOUR = (40, 200, 80)
CLAMPED_COLOUR = (230, 40, 40)


def map_stylus(stylus: np.ndarray, offset: np.ndarray, scale: float) -> np.ndarray:
    """Foot target in the thorax frame [m] for a stylus displacement [m] (thesis 3.3)."""
    return np.asarray(offset, dtype=float) + scale * np.asarray(stylus, dtype=float)


@dataclass
class LegTarget:
    """State of one teleoperated leg.

    Attributes
    ----------
    leg : str
    joints : ndarray of int
        Indices of the leg's three joints in the simulation.
    table : DHTable
        The leg's DH table (thorax frame).
    home : ndarray (3,)
        Foot position [m] in the thorax frame at the reset pose.
    target : ndarray (3,)
        Latest foot target [m] (thorax frame).
    result : IKResult or None
        Latest IK answer; ``result.reachable`` is False for a clamped target.
    """

    leg: str
    joints: np.ndarray
    table: DHTable
    home: np.ndarray
    target: np.ndarray
    result: IKResult | None = None
    nodes: dict[str, viser.SceneNodeHandle] = field(default_factory=dict, repr=False)

    @property
    def clamped(self) -> bool:
        """Whether the latest target was out of reach (clamped)."""
        return self.result is not None and not self.result.reachable


class FootTeleoperation:
    """Stylus gizmos for the front feet, mapped through offset/scale and IK to references.

    Parameters
    ----------
    server : viser.ViserServer
    simulation : RobotSimulation
    home_angles : ndarray
        Joint angles [rad] of the reset pose (all simulated joints); they define the
        home foot positions.
    scale : float
        Stylus-to-foot scale (thesis 3.3).
    lock : threading.RLock, optional
        Held while a gizmo drag commands the simulation (shared with its stepping thread).
    """

    def __init__(self, server: viser.ViserServer, simulation: RobotSimulation,
                 home_angles: np.ndarray, scale: float = 1.0,
                 lock: threading.RLock | None = None) -> None:
        self.server = server
        self.lock = lock if lock is not None else threading.RLock()
        self.simulation = simulation
        self.scale = scale
        self.shift = np.zeros(3)
        self.enabled = True
        robot = simulation.robot
        self.thorax_frame = server.scene.add_frame("/teleop", show_axes=False)
        self.legs: dict[str, LegTarget] = {}
        for leg in FRONT_LEGS:
            if leg not in robot.legs:
                continue
            first = robot.joint_names.index(f"{leg}_alpha")
            joints = np.arange(first, first + 3)
            table = leg_dh_table(robot, leg)
            home = np.asarray(thorax_frame_points(table, home_angles[joints]), dtype=float)
            state = LegTarget(leg, joints, table, home, home.copy())
            self.legs[leg] = state
            self._add_nodes(state)

    def _add_nodes(self, state: LegTarget) -> None:
        scene, leg = self.server.scene, state.leg
        origin = scene.add_frame(f"/teleop/{leg}", show_axes=False, position=state.home)
        gizmo = scene.add_transform_controls(
            f"/teleop/{leg}/stylus", scale=0.12, disable_rotations=True, depth_test=False,
        )
        gizmo.on_update(lambda _event, leg=leg: self.apply(leg))
        target = scene.add_icosphere(f"/teleop/{leg}_target", radius=0.018,
                                     color=REACHABLE_COLOUR, position=state.home)
        reached = scene.add_icosphere(f"/teleop/{leg}_reached", radius=0.012,
                                      color=(250, 250, 250), position=state.home,
                                      opacity=0.7)
        state.nodes.update(origin=origin, stylus=gizmo, target=target, reached=reached)

    def stylus(self, leg: str) -> np.ndarray:
        """Present stylus displacement [m] (the gizmo's position in its origin frame)."""
        return np.asarray(self.legs[leg].nodes["stylus"].position, dtype=float)

    def set_stylus(self, leg: str, displacement: np.ndarray) -> IKResult | None:
        """Move the stylus gizmo programmatically and apply it (as a drag would)."""
        self.legs[leg].nodes["stylus"].position = np.asarray(displacement, dtype=float)
        return self.apply(leg)

    def apply(self, leg: str) -> IKResult | None:
        """Map the stylus of ``leg`` to a foot target, solve IK, command the joints."""
        with self.lock:
            return self._apply(leg)

    def _apply(self, leg: str) -> IKResult:
        state = self.legs[leg]
        state.target = map_stylus(self.stylus(leg), state.home + self.shift, self.scale)
        simulation = self.simulation
        current = simulation.joint_angles()[state.joints]
        state.result = solve_leg(state.table, state.target, current, clamp=True)
        colour = CLAMPED_COLOUR if state.clamped else REACHABLE_COLOUR
        state.nodes["target"].position = state.target
        state.nodes["target"].color = colour
        state.nodes["reached"].position = state.result.foot
        if self.enabled:
            simulation.command_angles(state.result.angles, state.joints)
        return state.result

    def apply_all(self) -> None:
        """Re-apply every leg (after a change of offset, scale or enabling)."""
        for leg, state in self.legs.items():
            state.nodes["origin"].position = state.home + self.shift
            self.apply(leg)

    def reset(self) -> None:
        """Styluses back to their origins; targets back home."""
        for state in self.legs.values():
            state.nodes["stylus"].position = np.zeros(3)
            state.nodes["origin"].position = state.home + self.shift
            state.target = state.home.copy()
            state.result = None
            state.nodes["target"].position = state.home
            state.nodes["target"].color = REACHABLE_COLOUR
            state.nodes["reached"].position = state.home

    def follow_thorax(self, position: np.ndarray, quaternion: np.ndarray) -> None:
        """Place the teleoperation frame on the thorax (world pose, quaternion w-x-y-z)."""
        self.thorax_frame.position = position
        self.thorax_frame.wxyz = quaternion

    def status(self) -> str:
        """One markdown line per leg: target, reached foot, clamped or not."""
        lines = []
        for leg, state in self.legs.items():
            if state.result is None:
                lines.append(f"**{leg}**: at home")
                continue
            flag = "**clamped** (out of reach)" if state.clamped else "reachable"
            lines.append(
                f"**{leg}**: {flag}, error {1000 * state.result.error:.1f} mm"
            )
        return "  \n".join(lines)

    def remove(self) -> None:
        """Remove the gizmos and markers from the scene."""
        for state in self.legs.values():
            for node in reversed(list(state.nodes.values())):
                node.remove()
        self.thorax_frame.remove()
        self.legs.clear()
