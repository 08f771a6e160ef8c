"""Can the cylinders carry the robot? The least supply pressure from statics.

A cylinder's largest force is its stall force: one chamber at the supply pressure, the
other at the exhaust pressure (eq 4.1.11 without friction,
:func:`pneumaquad.core.physics.force.piston_force`), less the seal's Coulomb friction
that any motion must overcome. Extending, the supply acts on the whole piston; retracting,
on the annulus only, so a cylinder pulls less than it pushes.

The force each cylinder must give follows from statics (:mod:`.stance_kernels`: the
weight shared by the feet about the centre of mass, through each leg's Jacobian and
the cylinders' moment arms), at three kinds of pose:

- **standing up**: the poses of the stand-up, from lying to standing, the whole weight
  on the four feet (the thorax lifted off the ground);
- **standing**: the standing pose, four feet;
- **walking**: the standing pose with each leg lifted in turn, the other three carrying
  a third of the weight each (the centre of mass at the centroid of their triangle: the
  most even share a crawl's three-legged support can have).

Each needs a supply pressure for each cylinder (the stall force equal to the demand plus
Coulomb friction, a linear equation in the supply pressure); the largest over the
cylinders and poses is the least supply pressure. It is a necessary condition, not a
sufficient one: the dynamics of rising, the feet sliding on the ground and the controllers'
errors all ask for more. Runs below it are refused; above it, the stance check
(:mod:`pneumaquad.robot.stance_check`) tells whether the robot stood.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pneumaquad.core.physics.force import piston_force
from pneumaquad.params.schema import ActuatorParameters
from pneumaquad.robot.scenarios import LYING_ANGLES, TUCKED_ANGLES, standing_height
from pneumaquad.robot.simulation import RobotSimulation
from pneumaquad.robot.stand_up import stand_up_path

from .stance_kernels import (
    StanceViews,
    centre_of_mass_into,
    cylinder_forces_into,
    normal_forces_into,
    stance_views,
    stance_workspace,
)

__all__ = ["FOUR_LEGGED_RISE_MARGIN", "SITUATIONS", "InsufficientSupplyError",
           "SupplyRequirement", "check_supply", "cylinder_demands", "four_legged_rise_path",
           "gauge_text", "least_supply_for_force", "rise_in_pairs", "rise_requirement",
           "stall_forces", "supply_requirements"]

Array = NDArray[np.float64]


def stall_forces(actuator: ActuatorParameters,
                 supply_pressure: float | None = None) -> tuple[float, float]:
    """Largest extending and retracting force [N] of a cylinder, Coulomb friction deducted.

    One chamber at ``supply_pressure`` [Pa absolute] (default: the actuator's), the other
    at its exhaust pressure; the atmosphere on the rod's cross-section (eq 4.1.11).
    Returns (extending, retracting), both as positive magnitudes.
    """
    cylinder, gas = actuator.cylinder, actuator.gas
    supply = actuator.supply.supply_pressure if supply_pressure is None else supply_pressure
    exhaust, friction = actuator.supply.exhaust_pressure, actuator.friction.coulomb_force
    extending = piston_force(supply, exhaust, gas.atmospheric_pressure, cylinder.cap_area,
                             cylinder.rod_area, cylinder.rod_cross_section)
    retracting = -piston_force(exhaust, supply, gas.atmospheric_pressure, cylinder.cap_area,
                               cylinder.rod_area, cylinder.rod_cross_section)
    return extending - friction, retracting - friction


def least_supply_for_force(actuator: ActuatorParameters, force: float) -> float:
    """Supply pressure [Pa absolute] whose stall force (:func:`stall_forces`) in the
    direction of ``force`` [N] (positive extending) equals its magnitude.

    The stall force is linear in the supply pressure: extending, p_s·A_cap − p_ex·A_rod −
    p_atm·A_x − F_c; retracting, p_s·A_rod + p_atm·A_x − p_ex·A_cap − F_c.
    """
    cylinder, gas = actuator.cylinder, actuator.gas
    exhaust, friction = actuator.supply.exhaust_pressure, actuator.friction.coulomb_force
    atmosphere = gas.atmospheric_pressure
    needed = abs(force) + friction
    if force >= 0.0:
        return (needed + exhaust * cylinder.rod_area
                + atmosphere * cylinder.rod_cross_section) / cylinder.cap_area
    return (needed + exhaust * cylinder.cap_area
            - atmosphere * cylinder.rod_cross_section) / cylinder.rod_area


def cylinder_demands(simulation: RobotSimulation, angles: Array, carried: Array,
                     views: StanceViews | None = None) -> Array:
    """Cylinder forces [N] (positive extending) that hold the robot still at ``angles``.

    The thorax is level at the height that puts the feet of ``angles`` on flat ground;
    the feet of ``carried`` (legs,) bool share the whole weight about the centre of mass
    (:func:`.stance_kernels.normal_forces_into`), the others are in the air. The
    simulation's state is changed (:meth:`~pneumaquad.robot.simulation.RobotSimulation.
    set_pose`).

    Parameters
    ----------
    simulation : RobotSimulation
        The free quadruped.
    angles : (3,) ndarray
        (alpha, beta, gamma) [rad] of every leg.
    carried : (legs,) ndarray of bool
    views : StanceViews, optional
        The simulation's :func:`.stance_kernels.stance_views` (made here if not given;
        they stay valid across poses, so a caller weighing many poses makes them once).

    Returns
    -------
    ndarray (joints,)
    """
    legs = len(simulation.robot.legs)
    height = standing_height(simulation, angles)
    simulation.set_pose(np.tile(angles, legs), thorax_position=np.array([0.0, 0.0, height]))
    views = stance_views(simulation) if views is None else views
    workspace = stance_workspace()
    weights = np.asarray(carried, dtype=float)
    normal = np.zeros(legs)
    if weights.sum() == 3.0:  # the centre of mass at the centroid of the support
        workspace.centre[:] = simulation.foot_positions()[weights > 0.0, :2].mean(axis=0)
    else:
        centre_of_mass_into(views.body_mass, views.body_centres, views.total_mass,
                            workspace.centre)
    if not normal_forces_into(views.site_positions, views.foot_sites, workspace.centre,
                              views.weight, weights, workspace, normal):
        raise ValueError("fewer than three feet cannot carry the robot")
    forces = np.zeros(simulation.robot.joint_count)
    cylinder_forces_into(views, np.ones(legs), normal, forces)
    return forces


#: The kinds of pose :func:`supply_requirements` weighs (module docstring).
SITUATIONS = ("standing up", "standing", "walking")


@dataclass(frozen=True)
class SupplyRequirement:
    """The least supply pressure of one kind of pose (module docstring).

    Attributes
    ----------
    situation : str
        "standing up", "standing" or "walking".
    pressure : float [Pa absolute]
    joint : str
        The cylinder that needs it.
    force : float [N]
        Its demand there (positive extending), Coulomb friction not included.
    angles : ndarray (3,) [rad]
        The leg pose where it is needed.
    """

    situation: str
    pressure: float
    joint: str
    force: float
    angles: Array


def supply_requirements(simulation: RobotSimulation, standing_angles: Array,
                        path: Array, situations: tuple[str, ...] = SITUATIONS
                        ) -> list[SupplyRequirement]:
    """The least supply pressure for standing up along ``path``, standing, and walking.

    Parameters
    ----------
    simulation : RobotSimulation
        The free quadruped; its state is restored afterwards.
    standing_angles : (3,) ndarray
        The standing pose [rad] of every leg.
    path : (samples, 3) ndarray
        Leg poses [rad] of the stand-up, lying to standing.

    situations : tuple of str
        Which of :data:`SITUATIONS` to compute.

    Returns
    -------
    list of SupplyRequirement
        One per situation asked, in the order of :data:`SITUATIONS`.
    """
    robot = simulation.robot
    legs = len(robot.legs)
    saved = simulation.snapshot()
    views = stance_views(simulation)
    try:
        four = np.ones(legs, dtype=bool)
        poses = {
            "standing up": [(pose, four) for pose in np.asarray(path, dtype=float)],
            "standing": [(standing_angles, four)],
            "walking": [(standing_angles, np.arange(legs) != lifted)
                        for lifted in range(legs)],
        }
        requirements = []
        for situation, cases in poses.items():
            if situation not in situations:
                continue
            best = None
            for angles, carried in cases:
                demands = cylinder_demands(simulation, angles, carried, views)
                for joint, force in enumerate(demands):
                    kind = robot.joint_types[joint]
                    pressure = least_supply_for_force(robot.actuators[kind], float(force))
                    if best is None or pressure > best.pressure:
                        best = SupplyRequirement(situation, pressure,
                                                 robot.joint_names[joint], float(force),
                                                 np.array(angles, dtype=float))
            assert best is not None
            requirements.append(best)
        return requirements
    finally:
        simulation.restore(saved)


PSI = 6894.757293168  # [Pa]

#: The four-legged rise is taken while the supply is at least this multiple of its
#: statics requirement (absolute pressures); below, the staged rise. Measured: the
#: four-legged rise stood at 1.12 (50.3 psig, 2.5 kg thorax) and stalled at 1.07
#: (3 kg thorax) and 1.03 (45 psig) (docs/robot.md).
FOUR_LEGGED_RISE_MARGIN = 1.10


class InsufficientSupplyError(ValueError):
    """The supply pressure is below what statics asks to stand or walk."""


def four_legged_rise_path(standing_angles: Array, samples: int = 21) -> Array:
    """Leg poses (samples, 3) [rad] of the four-legged rise from lying into
    ``standing_angles`` (:func:`pneumaquad.robot.stand_up.stand_up_path`; the largest
    demand is near the lying pose, its first sample)."""
    return stand_up_path(np.linspace(0.0, 1.0, samples), standing_angles, LYING_ANGLES,
                         TUCKED_ANGLES)


def rise_requirement(simulation: RobotSimulation, standing_angles: Array) -> SupplyRequirement:
    """:func:`supply_requirements`' "standing up" of the four-legged rise into
    ``standing_angles`` (3,) [rad] (:func:`four_legged_rise_path`)."""
    path = four_legged_rise_path(standing_angles)
    return supply_requirements(simulation, standing_angles, path, ("standing up",))[0]


def rise_in_pairs(simulation: RobotSimulation, standing_angles: Array) -> bool:
    """Whether to stand up a pair of legs at a time (staged): the supply is below
    :data:`FOUR_LEGGED_RISE_MARGIN` times the four-legged rise's requirement."""
    needed = rise_requirement(simulation, standing_angles).pressure
    return bool(simulation.supply_pressure() < FOUR_LEGGED_RISE_MARGIN * needed)


def gauge_text(pressure: float, atmosphere: float) -> str:
    """An absolute pressure [Pa] as gauge text in psig and kPa (for messages)."""
    gauge = pressure - atmosphere
    return f"{gauge / PSI:.1f} psig ({gauge / 1e3:.0f} kPa gauge)"


def check_supply(simulation: RobotSimulation, standing_angles: Array,
                 walking: bool) -> None:
    """Refuse a supply below the least pressure at which the robot can stand (and, with
    ``walking``, walk) once up (:func:`supply_requirements`: four feet, or three).

    Raises
    ------
    InsufficientSupplyError
        Naming the supply, the least pressure, the cylinder that limits it and the mass.
    """
    situations = ("standing", "walking") if walking else ("standing",)
    requirements = supply_requirements(simulation, standing_angles,
                                       np.empty((0, 3)), situations)
    limiting = max(requirements, key=lambda requirement: requirement.pressure)
    supply = simulation.supply_pressure()
    if supply >= limiting.pressure:
        return
    atmosphere = simulation.atmospheric_pressure()
    mass = float(simulation.model.body_mass.sum())
    raise InsufficientSupplyError(
        f"the supply, {gauge_text(supply, atmosphere)}, is below the "
        f"{gauge_text(limiting.pressure, atmosphere)} at which the cylinders can "
        f"hold the {mass:.2f} kg robot {limiting.situation} (statics: {limiting.joint} "
        f"needs {abs(limiting.force):.0f} N plus its Coulomb friction); raise "
        "actuators.supply_pressure or lighten the robot")
