"""Force balance on the piston (thesis 4.1.3)."""

import math

from pneumaquad.core.jit import compiled


@compiled
def piston_force(
    cap_pressure: float,
    rod_pressure: float,
    atmospheric_pressure: float,
    cap_area: float,
    rod_area: float,
    rod_cross_section: float,
) -> float:
    """Pneumatic force on the piston, eq 4.1.11 without the friction term.

    F = P_cap·A_cap - P_rod·A_rod - P_atm·A_rod_cross_section, positive extending; the
    atmosphere acts on the rod's cross-section where it leaves the cylinder.

    Parameters
    ----------
    cap_pressure, rod_pressure, atmospheric_pressure : float
        Absolute pressures [Pa].
    cap_area, rod_area, rod_cross_section : float
        Piston area, annulus area and rod cross-section [m^2].

    Returns
    -------
    float
        Force [N].
    """
    return (
        cap_pressure * cap_area - rod_pressure * rod_area - atmospheric_pressure * rod_cross_section
    )


@compiled
def gravity_force(mass: float, gravity: float, orientation_angle: float) -> float:
    """Weight of the moving mass along the extension direction.

    Parameters
    ----------
    mass : float
        Moving mass [kg].
    gravity : float
        g [m/s^2].
    orientation_angle : float
        Angle of the extension direction below the horizontal [rad]: +pi/2 for a rod
        pointing down (gravity extends), -pi/2 for a rod pointing up.

    Returns
    -------
    float
        Force along +x [N].
    """
    return mass * gravity * math.sin(orientation_angle)


@compiled
def end_stop_force(
    position: float, velocity: float, stroke: float, stiffness: float, damping: float
) -> float:
    """Reaction of the cylinder's end stops as a one-sided spring-damper.

    Parameters
    ----------
    position, velocity : float
        Piston extension [m] and its rate [m/s].
    stroke : float
        Stroke [m]; the stops are at 0 and stroke.
    stiffness, damping : float
        Contact stiffness [N/m] and damping [N s/m].

    Returns
    -------
    float
        Force along +x [N]; it only pushes away from the stop, never pulls.
    """
    if position < 0.0:
        return max(0.0, -stiffness * position - damping * velocity)
    if position > stroke:
        return min(0.0, -stiffness * (position - stroke) - damping * velocity)
    return 0.0
