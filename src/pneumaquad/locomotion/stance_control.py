"""Force-controlled stance for walking: the stance legs share the load as statics asks.

A quadruped standing on four position-controlled legs is statically indeterminate: a
millimetre of leg-length error decides whether a foot carries its share of the weight or
none of it, and a leg that lifts throws its load onto the others at once. On the
pneumatic legs, whose PID on piston position only builds force through position error,
the robot then rocks onto diagonal pairs of feet, the unloaded corner sags, and the
stance feet are pushed sideways.

Here every stance leg is instead *told* its load, once per control chunk:

1. each leg's **load share** (:func:`load_shares`) rises from 0 just after touchdown and
   falls back to 0 before lift-off, so the load moves off a leg before it lifts (the
   gait's transfer gap, :attr:`pneumaquad.gait.crawl.CrawlGait.transfer_gap`, gives the
   front legs four feet down for this);
2. the desired **normal force** of each foot is the least-variation distribution of the
   robot's weight that balances it about the measured centre of mass
   (:func:`desired_normal_forces`);
3. the **cylinder forces** that hold that foot force in statics follow through the leg's
   Jacobian and the cylinders' moment arms (:func:`cylinder_forces_for_foot_force`);
4. the cylinders **track** these forces (:meth:`.RobotSimulation.track_forces`: the valve
   voltage gets ``k_F·(F_set − F)`` added and the PID's integral is off), so the position
   loop only adds a spring of stiffness Kp / k_F about the planned foot position.

A swinging leg (share 0) is under plain position control.

The per-chunk arithmetic is compiled (:mod:`.stance_kernels`); the functions of this
module with array arguments are its reference in NumPy.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pneumaquad.core.jit import load_compiled
from pneumaquad.gait.crawl import CrawlGait
from pneumaquad.robot.simulation import RobotSimulation

from .feedback_kernels import gait_timing
from .stance_kernels import (
    centre_of_mass_into,
    cylinder_forces_into,
    normal_forces_into,
    stance_step,
    stance_views,
    stance_workspace,
)
from .walk_settings import StanceControlSettings

__all__ = ["StanceControlSettings", "StanceController", "StanceLoads", "StanceSettle",
           "cylinder_forces_for_foot_force", "desired_normal_forces", "load_shares",
           "track_stance_loads"]

Array = NDArray[np.float64]


def load_shares(phases: ArrayLike, duty_factor: float, rise: float, fall: float) -> Array:
    """Load share in [0, 1] of each leg at its gait phase.

    Parameters
    ----------
    phases : array_like (..., legs)
        Cycle fraction since the leg's lift-off, in [0, 1) (:func:`.crawl.leg_phases`).
    duty_factor : float
        Stance fraction β; the leg swings for phases below 1 − β (share 0).
    rise, fall : float
        Cycle fractions of the linear rise after touchdown and of the linear fall that
        ends at lift-off.
    """
    phase = np.asarray(phases, dtype=float)
    touchdown = 1.0 - duty_factor
    rising = (phase - touchdown) / rise
    falling = (1.0 - phase) / fall
    return np.clip(np.minimum(rising, falling), 0.0, 1.0)


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


def cylinder_forces_for_foot_force(jacobian: ArrayLike, bias_torques: ArrayLike,
                                   moment_arms: ArrayLike, foot_force: ArrayLike) -> Array:
    """Cylinder forces [N] that hold a leg in statics with ``foot_force`` on its foot.

    The leg's joint torques must balance the gravity (and velocity) torques and the
    ground's push on the foot: ``τ = bias − Jᵀ f``; each cylinder gives τᵢ = rᵢ·Fᵢ with
    rᵢ = d(cylinder length)/d(joint angle), so ``Fᵢ = τᵢ / rᵢ``.

    Parameters
    ----------
    jacobian : (3, joints) [m/rad]
        Foot position Jacobian w.r.t. the leg's joints, in the frame of ``foot_force``.
    bias_torques : (joints,) [N·m]
        MuJoCo's ``qfrc_bias`` at the leg's joints (gravity of the leg's links).
    moment_arms : (joints,) [m]
        Cylinder moment arms (:func:`.linkage.moment_arm`), non-zero.
    foot_force : (3,) [N]
        Force the ground exerts on the foot.
    """
    torques = np.asarray(bias_torques, dtype=float) - np.asarray(jacobian, dtype=float).T @ (
        np.asarray(foot_force, dtype=float))
    return torques / np.asarray(moment_arms, dtype=float)


class StanceLoads:
    """Cylinder force set-points of the stance legs of one simulation, as statics asks.

    Holds the simulation's :class:`.stance_kernels.StanceViews` and a workspace, so a call
    runs the compiled arithmetic of :mod:`.stance_kernels` and two calls into the
    simulation (force tracking for the loaded legs' cylinders, plain position control for
    the others).

    Parameters
    ----------
    simulation : RobotSimulation
        Read (feet, centre of mass, Jacobians, joint angles) and commanded (force
        set-points).
    """

    def __init__(self, simulation: RobotSimulation) -> None:
        self.simulation = simulation
        self.views = stance_views(simulation)
        self.workspace = stance_workspace()
        legs = len(self.views.foot_sites)
        self.set_points = np.zeros(3 * legs)  # [N] of the loaded legs' cylinders
        joints = [simulation.robot.joint_names.index(f"{leg}_alpha") + np.arange(3)
                  for leg in simulation.robot.legs]
        # per set of loaded legs (bits): the joints that track and those that do not
        self._tracked = [np.concatenate([joints[leg] for leg in range(legs) if bits >> leg & 1]
                                        + [np.zeros(0, dtype=int)]) for bits in range(2**legs)]
        self._released = [np.concatenate([joints[leg] for leg in range(legs)
                                          if not bits >> leg & 1] + [np.zeros(0, dtype=int)])
                          for bits in range(2**legs)]

    def fallback_normal_forces(self, shares: Array, normal: Array) -> None:
        """Normal forces [N] into ``normal`` by :func:`desired_normal_forces` (least
        squares), where the compiled elimination refused the system."""
        normal[:] = desired_normal_forces(self.simulation.foot_positions(),
                                          self.workspace.centre, self.views.weight, shares)

    def apply(self, loaded: int, force_gain: float, stiffness: float) -> None:
        """Track ``self.set_points`` on the cylinders of the ``loaded`` legs (bits) with
        ``force_gain`` [V/N] and ``stiffness``; plain position control for the others."""
        tracked, released = self._tracked[loaded], self._released[loaded]
        if len(released):
            self.simulation.stop_force_tracking(released)
        if len(tracked):
            self.simulation.track_forces(self.set_points[: len(tracked)], force_gain, tracked,
                                         stiffness)

    def track(self, shares: ArrayLike, force_gain: float, stiffness: float = 1.0) -> Array:
        """:func:`track_stance_loads` for this simulation; returns the desired normal
        forces (legs,) [N]."""
        shares = np.array(shares, dtype=float)
        normal = np.zeros(len(shares))
        views = self.views
        centre_of_mass_into(views.body_mass, views.body_centres, views.total_mass,
                            self.workspace.centre)
        if not normal_forces_into(views.site_positions, views.foot_sites,
                                  self.workspace.centre, views.weight, shares,
                                  self.workspace, normal):
            self.fallback_normal_forces(shares, normal)
        loaded = cylinder_forces_into(views, shares, normal, self.set_points)
        self.apply(loaded, force_gain, stiffness)
        return normal


def track_stance_loads(simulation: RobotSimulation, shares: ArrayLike,
                       force_gain: float, stiffness: float = 1.0) -> Array:
    """Set every leg's cylinders to carry its statics share of the robot's weight.

    The desired normal forces (:func:`desired_normal_forces`, weights ``shares`` (legs,),
    the whole robot's weight about its measured centre of mass) become each leg's
    cylinder force set-points (:func:`cylinder_forces_for_foot_force`, vertical foot force,
    the leg's Jacobian and gravity torques at the present state), tracked with
    ``force_gain`` [V/N]; legs of share 0 return to plain position control. (Compiled,
    :mod:`.stance_kernels`; :class:`StanceLoads` keeps what this gathers for repeated
    calls.)

    Returns the desired normal forces (legs,) [N].
    """
    return StanceLoads(simulation).track(shares, force_gain, stiffness)


class StanceController:
    """Force-controlled stance while walking: references pass through, forces are set.

    Call it like a reference function, once per control chunk (a feedback phase): it sets
    the force set-points of every stance leg from the simulation's present state
    (:func:`track_stance_loads` with the gait's :func:`load_shares`) and returns
    ``references(times)`` unchanged.

    Parameters
    ----------
    simulation : RobotSimulation
        Read (feet, centre of mass, Jacobians, joint angles) and commanded (force set-points)
        at every call.
    gait : CrawlGait
        The gait being walked (leg phases).
    start : float [s]
        Simulation time of the gait's t = 0.
    references : callable
        ``f(times) -> (len(times), joints)`` planned joint angles [rad].
    settings : StanceControlSettings
    """

    def __init__(self, simulation: RobotSimulation, gait: CrawlGait, start: float,
                 references, settings: StanceControlSettings | None = None) -> None:
        self.simulation = simulation
        self.gait = gait
        self.start = start
        self.references = references
        self.settings = settings or StanceControlSettings()
        self.loads = StanceLoads(simulation)
        self.timing = gait_timing(gait)
        legs = len(self.timing.offsets)
        self._log = np.zeros((64, 1 + 2 * legs))
        self._logged = 0
        load_compiled(stance_step, *self._step_arguments(0.0, np.zeros(legs), np.zeros(legs)))

    @property
    def log(self) -> Array:
        """Rows of (time [s], load shares (legs), desired normal forces (legs) [N]), one
        per call (a copy)."""
        return self._log[: self._logged].copy()

    def _update(self) -> Array:
        """Set the force set-points for the present state; the log row written."""
        simulation, settings, loads = self.simulation, self.settings, self.loads
        if self._logged == len(self._log):
            self._log = np.concatenate([self._log, np.zeros_like(self._log)])
        row = self._log[self._logged]
        self._logged += 1
        legs = len(self.timing.offsets)
        time = simulation.time
        row[0] = time
        shares, normal = row[1 : 1 + legs], row[1 + legs :]
        loaded = stance_step(*self._step_arguments(time - self.start, shares, normal))
        if loaded < 0:
            loads.fallback_normal_forces(shares, normal)
            loaded = cylinder_forces_into(loads.views, shares, normal, loads.set_points)
        loads.apply(loaded, settings.force_gain, settings.stiffness)
        return normal

    def _step_arguments(self, gait_time: float, shares: Array, normal: Array) -> tuple:
        """:func:`.stance_kernels.stance_step`'s arguments at ``gait_time`` [s], into
        ``shares`` and ``normal`` (legs,)."""
        settings, loads = self.settings, self.loads
        return (loads.views, self.timing, gait_time, settings.rise, settings.fall,
                loads.workspace, shares, normal, loads.set_points)

    def update(self) -> Array:
        """Set the force set-points for the present state; return the desired normal
        forces (legs,) [N]."""
        return self._update().copy()

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """Planned joint references (len(times), joints) [rad] for the next chunk."""
        self._update()
        return self.references(times)


class StanceSettle:
    """Four feet down, each carrying its statics share: a pose held under force control.

    Call it like a reference function, once per control chunk (a feedback phase): every
    leg's cylinders track the forces that carry the robot's weight about its measured
    centre of mass (:meth:`StanceLoads.track`, all shares 1), and the pose ``pose``
    (joints,) [rad] is returned for every time. Held so, the legs stop pushing against
    each other through the feet's friction: a staged rise (feet stepped while the others
    held position with their integrals) leaves internal forces of over 100 N that a leg
    must shed before it can lift, and the PID integrals are off while a leg tracks force,
    so a leg that then swings starts from its statics load and no wound-up integral.

    Parameters
    ----------
    simulation : RobotSimulation
    pose : array_like (joints,) [rad]
    settings : StanceControlSettings, optional
        The force gain and stiffness of the walk's stance.
    """

    def __init__(self, simulation: RobotSimulation, pose: ArrayLike,
                 settings: StanceControlSettings | None = None) -> None:
        self.loads = StanceLoads(simulation)
        self.pose = np.asarray(pose, dtype=float)
        self.settings = settings or StanceControlSettings()
        self.shares = np.ones(len(simulation.robot.legs))

    def __call__(self, times: np.ndarray) -> np.ndarray:
        """The held pose (len(times), joints) [rad]; the force set-points updated."""
        self.loads.track(self.shares, self.settings.force_gain, self.settings.stiffness)
        return np.broadcast_to(self.pose, (len(times), self.pose.size))
