"""Force-controlled stance on the simulated quadruped: four stiff legs on the ground are
statically indeterminate; tracking the statics' forces resolves it."""

from __future__ import annotations

import numpy as np
import pytest

from pneumaquad.locomotion.stance_control import track_stance_loads
from pneumaquad.params import load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.simulation import RobotSimulation


def _stand_with_a_leg_length_error(error_degrees: float, shares: np.ndarray | None,
                                   seal_friction: bool = True):
    """Stand, then command front_left beta ``error_degrees`` off the standing pose for 3 s;
    with ``shares`` the stance legs track their load. Returns (measured, desired) [N]."""
    from pneumaquad.robot.scenarios import STANDING_ANGLES, standing_height

    sim = RobotSimulation(build_robot(load_robot("crr-quadruped"), "quadruped"))
    if not seal_friction:
        sim.seal["static_force"] = sim.seal["coulomb_force"] = 0.0
    pose = np.tile(STANDING_ANGLES, 4)  # gamma 90°: legs nearly upright under the hips
    height = standing_height(sim, STANDING_ANGLES) + 0.003
    sim.set_pose(pose, thorax_position=np.array([0.0, 0.0, height]))
    sim.command_angles(pose)
    sim.step(1000)
    reference = pose.copy()
    reference[sim.robot.joint_names.index("front_left_beta")] += np.radians(error_degrees)
    table = np.tile(reference, (10, 1))
    desired = None
    for _ in range(300):
        if shares is not None:
            desired = track_stance_loads(sim, shares, force_gain=0.01)
        sim.step(10, table, 0)
    return sim.foot_normal_forces(), desired


def test_position_control_rocks_onto_a_diagonal_and_force_tracking_shares_the_load():
    weight = 50.66  # [N] the model's mass (5.164 kg) times g
    rigid, _ = _stand_with_a_leg_length_error(2.0, None)
    # the longer front_left leg and its diagonal partner rear_right carry the robot
    assert rigid.sum() == pytest.approx(weight, rel=0.02)
    assert min(rigid[0], rigid[3]) > 1.8 * max(rigid[1], rigid[2])  # measured 17.4 vs 7.9 N
    tracked, desired = _stand_with_a_leg_length_error(2.0, np.ones(4))
    assert desired.sum() == pytest.approx(weight, rel=1e-3)
    assert tracked == pytest.approx(desired, abs=1.5)  # measured within 0.72 N


def test_uneven_shares_are_tracked_where_seal_stiction_does_not_hold_the_legs():
    # Moving load along the diagonals of a robot standing still needs no motion, so the
    # cylinders' seal stiction (breakaway 20 N, App. C.1.1) can hold part of it (how much
    # depends on the pose: docs/robot.md). Without seal friction the statics' share is
    # what the feet carry.
    shares = np.array([1.0, 1.0, 1.0, 0.25])
    tracked, desired = _stand_with_a_leg_length_error(0.0, shares, seal_friction=False)
    # the light foot and its diagonal partner carry less (the twist mode), the others more
    assert desired[3] < desired[1] - 2.0 and desired[0] < desired[2] - 2.0
    assert tracked == pytest.approx(desired, abs=1.5)  # measured within 0.35 N
