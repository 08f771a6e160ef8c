"""Stance control for walking: load sharing between the stance feet and body levelling.

A quadruped on four position-controlled legs is statically indeterminate: a millimetre of
leg-length error decides whether a foot carries its share of the weight or none of it, and
stiff pneumatic joints (hundreds of newtons per cylinder against a 60 N robot) turn such
errors into a body rocking on one diagonal pair of feet. The planned foot positions of the
crawl gait are therefore corrected, every control chunk, by two slow loops on the vertical
foot positions (body frame):

* **load sharing** — the desired normal force of each stance foot is the weighted
  least-norm distribution of the measured total load that balances the centre of mass
  (:func:`desired_normal_forces`); a leg about to lift and a leg just touched down get a
  small weight (:func:`stance_weights`), so the load moves off a leg before it lifts.
  The force errors are integrated into foot offsets (admittance, [m/(N·s)]) and only their
  *twist* part is kept (:func:`twist_component`): the part that changes how the load is
  shared without tilting or lifting the body.
* **levelling** — the body's measured tilt is integrated into a plane of foot offsets
  (the feet on the low side reach further down), so tracking errors and sloped ground do
  not leave the body tilted.

The corrected foot positions become joint-angle corrections through the leg Jacobian at
the planned angles (:func:`pneumaquad.robot.kinematics.foot_jacobian`), added to the
planned joint references; offsets are a few millimetres, well inside the linear range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pneumaquad.gait.crawl import CrawlGait, leg_phases, stance_flags
from pneumaquad.gait.stability import centre_of_mass
from pneumaquad.gait.walk import WalkPlan, thorax_rotation

from .legs import leg_dh_table, shift_feet
from .simulation import RobotSimulation

__all__ = ["StanceControlGains", "StanceController", "desired_normal_forces",
           "stance_weights", "twist_component"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class StanceControlGains:
    """Gains of the stance control.

    Attributes
    ----------
    force_gain : float [m/(N·s)]
        Foot offset speed per newton of normal-force error (load sharing).
    attitude_gain : float [1/s]
        Levelling: rate at which the measured tilt is taken into the foot plane.
    height_gain : float [1/s]
        Rate at which the error of the body's height above its stance feet is taken into
        a common foot offset (the legs sag under the load of a lifted leg).
    offset_limit : float [m]
        Largest foot offset either loop may command.
    transfer : float
        Cycle fraction over which a leg's weight rises after touchdown and falls before
        lift-off (load transfer).
    swing_decay : float [s]
        Time constant with which a swinging leg's load-sharing offset returns to zero.
    force_filter : float [s]
        Time constant of the first-order low-pass filter on the measured foot forces
        (contact forces of stiff pneumatic legs chatter at tens of hertz).
    """

    force_gain: float = 4e-4
    attitude_gain: float = 2.0
    height_gain: float = 2.0
    offset_limit: float = 0.03
    transfer: float = 0.08
    swing_decay: float = 0.2
    force_filter: float = 0.05


def stance_weights(phases: ArrayLike, duty_factor: float, transfer: float) -> Array:
    """Load-sharing weight in [0, 1] of each leg at its gait phase.

    Parameters
    ----------
    phases : array_like (..., legs)
        Cycle fraction since the leg's lift-off, in [0, 1) (:func:`.crawl.leg_phases`).
    duty_factor : float
        Stance fraction β; the leg swings for phases below 1 − β (weight 0).
    transfer : float
        Cycle fraction of the linear rise after touchdown and of the fall before lift-off.
    """
    phase = np.asarray(phases, dtype=float)
    touchdown = 1.0 - duty_factor
    if transfer <= 0.0:
        return (phase >= touchdown).astype(float)
    rise = (phase - touchdown) / transfer
    fall = (1.0 - phase) / transfer
    return np.clip(np.minimum(rise, fall), 0.0, 1.0)


def desired_normal_forces(feet_xy: ArrayLike, com_xy: ArrayLike, total_load: float,
                          weights: ArrayLike) -> Array:
    """Normal forces [N] of the feet that carry ``total_load`` [N] about the centre of mass.

    The least Σ Fᵢ²/wᵢ distribution with Σ Fᵢ = W and Σ Fᵢ·pᵢ = W·c (force and moment
    balance about the horizontal axes; pᵢ the feet, c the centre-of-mass projection, in
    any common horizontal frame [m]). Feet of weight 0 carry nothing. Three feet give the
    unique statically determinate answer; four share it with least variation. With the
    centre of mass outside the support the exact answer would need a pulling foot: such
    forces are set to 0 and the rest rescaled to the total.
    """
    feet = np.asarray(feet_xy, dtype=float)[:, :2]
    weight = np.clip(np.asarray(weights, dtype=float), 0.0, None)
    forces = np.zeros(len(feet))
    active = weight > 0.0
    if total_load <= 0.0 or not np.any(active):
        return forces
    balance = np.vstack([np.ones(active.sum()), feet[active].T])  # (3, k)
    target = total_load * np.array([1.0, *np.asarray(com_xy, dtype=float)[:2]])
    scaled = balance * weight[active]
    multipliers = np.linalg.lstsq(scaled @ balance.T, target, rcond=1e-9)[0]
    share = weight[active] * (balance.T @ multipliers)
    share = np.clip(share, 0.0, None)
    if share.sum() > 0.0:
        share *= total_load / share.sum()
    forces[active] = share
    return forces


def twist_component(offsets: ArrayLike, feet_xy: ArrayLike, mask: ArrayLike) -> Array:
    """The part of the vertical foot ``offsets`` [m] that does not move or tilt the body.

    Among the feet in ``mask`` the least-squares plane a + b·x + c·y through the offsets
    (which would lift and tilt the body) is removed; with three feet or fewer nothing is
    left. Feet outside ``mask`` get 0.
    """
    offsets = np.asarray(offsets, dtype=float)
    mask = np.asarray(mask, dtype=bool)
    result = np.zeros_like(offsets)
    if mask.sum() <= 3:
        return result
    feet = np.asarray(feet_xy, dtype=float)[mask, :2]
    plane = np.column_stack([np.ones(len(feet)), feet])
    coefficients = np.linalg.lstsq(plane, offsets[mask], rcond=None)[0]
    result[mask] = offsets[mask] - plane @ coefficients
    return result


class StanceController:
    """Walking references with load sharing and levelling, one call per control chunk.

    Parameters
    ----------
    simulation : RobotSimulation
        Read (foot forces, feet, centre of mass, thorax attitude) at every call.
    gait : CrawlGait
        The gait ``plan`` was made from.
    plan : WalkPlan
        Planned joint references at the control rate (:func:`.gait.walk.plan_walk`).
    start : float [s]
        Simulation time of the plan's first row.
    gains : StanceControlGains
    """

    def __init__(self, simulation: RobotSimulation, gait: CrawlGait, plan: WalkPlan,
                 start: float, gains: StanceControlGains | None = None) -> None:
        self.simulation = simulation
        self.gait = gait
        self.plan = plan
        self.start = start
        self.gains = gains or StanceControlGains()
        robot = simulation.robot
        self.tables = [leg_dh_table(robot, leg) for leg in robot.legs]
        self.to_thorax = thorax_rotation(robot).T  # body → thorax frame
        self.load_offsets = np.zeros(len(robot.legs))  # [m] down = positive
        self.tilt = np.zeros(2)  # [m/m] levelling plane slopes along body x, y
        self.lift = 0.0  # [m] common offset of the height loop
        self.forces: Array | None = None  # [N] filtered foot normal forces
        self.last_time: float | None = None
        self.log: list[Array] = []

    def _rows(self, times: Array) -> Array:
        step = self.simulation.control_step
        index = np.clip(np.round((times - self.start) / step).astype(int), 0,
                        len(self.plan.references) - 1)
        return self.plan.references[index]

    def _body_to_world(self) -> Array:
        data, robot = self.simulation.data, self.simulation.robot
        return data.xmat[robot.thorax_id].reshape(3, 3) @ self.to_thorax

    def update(self, interval: float) -> Array:
        """Integrate both loops over ``interval`` [s]; return the foot offsets (legs,) [m]
        (positive = foot further down in the body frame)."""
        simulation, gains = self.simulation, self.gains
        time = simulation.time - self.start
        phases = leg_phases(self.gait, np.array([time]))[0]
        weights = stance_weights(phases, self.gait.duty_factor, gains.transfer)
        planned = stance_flags(self.gait, np.array([time]))[0]
        measured = simulation.foot_normal_forces()
        if self.forces is None:
            self.forces = measured
        else:
            blend = 1.0 - np.exp(-interval / gains.force_filter)
            self.forces = self.forces + blend * (measured - self.forces)
        forces = self.forces
        feet_world = simulation.foot_positions()
        com = centre_of_mass(simulation.model, simulation.data)
        desired = desired_normal_forces(feet_world, com, float(forces.sum()), weights)
        body_feet = self.plan.cycle.feet[0] @ self.to_thorax  # body-frame feet (any sample)
        error = np.where(planned, desired - forces, 0.0)
        self.load_offsets += gains.force_gain * error * interval
        self.load_offsets = np.where(
            planned, twist_component(self.load_offsets, body_feet, planned),
            self.load_offsets * np.exp(-interval / gains.swing_decay),
        )
        body_to_world = self._body_to_world()
        self.tilt += gains.attitude_gain * interval * body_to_world[2, :2]
        limit = gains.offset_limit
        self.tilt = np.clip(self.tilt, -1.0, 1.0)
        loaded = planned & (forces > 0.0)
        if np.any(loaded):
            thorax = simulation.data.xpos[simulation.robot.thorax_id]
            height = thorax[2] - feet_world[loaded, 2].mean()
            planned_height = -body_feet[loaded, 2].mean()
            self.lift = float(np.clip(
                self.lift + gains.height_gain * interval * (planned_height - height),
                -limit, limit))
        plane = -(body_feet[:, :2] @ self.tilt)
        offsets = np.clip(self.load_offsets + plane + self.lift, -limit, limit)
        self.log.append(np.concatenate([[simulation.time], forces, desired, offsets]))
        return offsets

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Joint references (len(times), joints) [rad] for the next chunk."""
        interval = 0.0 if self.last_time is None else self.simulation.time - self.last_time
        self.last_time = self.simulation.time
        offsets = self.update(interval)
        rows = self._rows(np.asarray(times, dtype=float))
        down = np.zeros((len(offsets), 3))
        down[:, 2] = -offsets
        return shift_feet(rows, self.tables, down @ self.to_thorax.T)
