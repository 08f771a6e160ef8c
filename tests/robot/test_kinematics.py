"""Tests of the leg kinematics: DH extraction, FK (DH vs MuJoCo), Jacobian, IK.

The real leg is rebuilt here from the SrLib link frames of thesis App. C.2.1 (Leg.cpp), so the
DH table is checked against thesis Table 1 by derivation, not by typed-in numbers. The
package's one forward kinematics (the compiled DH chain) is checked against MuJoCo's own
kinematics of the same geometry: three hinges and a foot site in a small MJCF model.
"""

from __future__ import annotations

import re
from functools import cache

import mujoco
import numpy as np
import pytest

from pneumaquad.robot.kinematics import (
    JOINT_NAMES,
    DHTable,
    LegGeometry,
    dh_frames,
    dh_from_geometry,
    foot_jacobian,
    format_dh_table,
    forward_kinematics_dh,
)
from pneumaquad.robot.leg_ik import UnreachableTargetError, inverse_kinematics

HALF_PI = np.pi / 2
LIMITS_DEG = np.array([[-47.0, 90.0], [-67.0, -1.0], [17.0, 95.0]])  # App. C.2.1 l.52, 63, 71


def _rotation(axis: int, angle: float) -> np.ndarray:
    cosine, sine = np.cos(angle), np.sin(angle)
    first, second = [(1, 2), (2, 0), (0, 1)][axis]
    rotation = np.eye(3)
    rotation[first, first] = rotation[second, second] = cosine
    rotation[first, second], rotation[second, first] = -sine, sine
    return rotation


def euler_zyx(angles: tuple[float, float, float], position: tuple[float, float, float]):
    """SrLib ``EulerZYX(Vec3(a, b, c), Vec3(x, y, z))``: Rz(a) Ry(b) Rx(c), then translation."""
    frame = np.eye(4)
    frame[:3, :3] = _rotation(2, angles[0]) @ _rotation(1, angles[1]) @ _rotation(0, angles[2])
    frame[:3, 3] = position
    return frame


def _joined(parent_frame: np.ndarray, child_frame: np.ndarray) -> np.ndarray:
    """Pose of the child link in the parent link at zero joint angle."""
    return parent_frame @ np.linalg.inv(child_frame)


def real_leg_geometry(lower_deg=LIMITS_DEG[:, 0], upper_deg=LIMITS_DEG[:, 1]) -> LegGeometry:
    """Leg geometry in the alpha joint frame, from the Leg.cpp frames (App. C.2.1)."""
    alpha_in_coxa1 = euler_zyx((0, HALF_PI, 0), (0, 0, 0.0731))
    coxa1 = np.linalg.inv(alpha_in_coxa1)  # coxa1 link pose in the alpha joint frame
    coxa2 = coxa1 @ _joined(
        euler_zyx((0, 0, 0), (0, 0, -0.0481)), euler_zyx((0, -HALF_PI, 0), (0, 0, -0.025))
    )
    beta_joint = coxa2 @ euler_zyx((0, 0, -HALF_PI), (0.025, 0, 0))
    femur = beta_joint @ np.linalg.inv(euler_zyx((0, HALF_PI, 0), (0, 0, 0.087)))
    gamma_joint = femur @ euler_zyx((0, HALF_PI, 0), (0, 0, -0.087))
    tibia = gamma_joint @ np.linalg.inv(euler_zyx((0, HALF_PI, 0), (0, 0, 0.152)))
    foot = tibia @ np.array([0.0, 0.0, -(0.255 / 2 + 0.015 / 2), 1.0])  # distal capsule tip
    frames = np.stack([np.eye(4), beta_joint, gamma_joint])  # joints turn about their z
    return LegGeometry(frames[:, :3, 3], frames[:, :3, 2], foot[:3], np.radians(lower_deg),
                       np.radians(upper_deg))


def _vector(values) -> str:
    return " ".join(repr(float(value)) for value in values)


@cache
def _mujoco_chain(geometry: LegGeometry) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The leg as a MuJoCo chain: hinges at the geometry's joint points and axes, a foot site.

    Every body sits at the origin without rotation, so positions given in a body are in the
    geometry frame at zero angles; MuJoCo then does its own forward kinematics."""
    hinges = [f'<body><joint type="hinge" limited="false" pos="{_vector(point)}" '
              f'axis="{_vector(axis)}"/><geom type="sphere" size="0.01"/>'
              for point, axis in zip(geometry.joint_points, geometry.joint_axes, strict=True)]
    xml = (f"<mujoco><worldbody>{''.join(hinges)}<site name=\"foot\" "
           f"pos=\"{_vector(geometry.foot_point)}\"/>{'</body>' * 3}</worldbody></mujoco>")
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model)


def mujoco_feet(geometry: LegGeometry, angles) -> np.ndarray:
    """Foot position(s) (..., 3) [m] that MuJoCo computes for joint angles (..., 3) [rad]."""
    model, data = _mujoco_chain(geometry)
    angles = np.asarray(angles, dtype=float)
    feet = np.empty(angles.shape)
    for index in np.ndindex(angles.shape[:-1]):
        data.qpos[:] = angles[index]
        mujoco.mj_kinematics(model, data)
        feet[index] = data.site_xpos[0]
    return feet


def mujoco_joint_axes(geometry: LegGeometry, angles) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's joint anchors and axes (3, 3) [m], [-] for one set of angles [rad]."""
    model, data = _mujoco_chain(geometry)
    data.qpos[:] = angles
    mujoco.mj_kinematics(model, data)
    return data.xanchor.copy(), data.xaxis.copy()


GEOMETRY = real_leg_geometry()
TABLE = dh_from_geometry(GEOMETRY)


def _random_angles(generator, count, lower=GEOMETRY.lower_limits, upper=GEOMETRY.upper_limits):
    return generator.uniform(lower, upper, size=(count, 3))


def _random_rotation(generator) -> np.ndarray:
    q, r = np.linalg.qr(generator.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _random_table(generator, table1_structure: bool) -> DHTable:
    if table1_structure:
        alpha = [generator.choice([-HALF_PI, HALF_PI]), 0.0, 0.0]
    else:
        alpha = [generator.choice([0.0, HALF_PI, -HALF_PI, generator.uniform(-3, 3)])
                 for _ in range(3)]
    a = [generator.choice([0.0, generator.uniform(0.05, 0.3)]) for _ in range(3)]
    if table1_structure:
        a[1], a[2] = generator.uniform(0.1, 0.3, size=2)
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = _random_rotation(generator), generator.normal(size=3) * 0.1
    tool = np.eye(4)
    tool[:3, 3] = generator.normal(size=3) * 0.03
    return DHTable(generator.uniform(-np.pi, np.pi, 3), generator.normal(size=3) * 0.05,
                   alpha, a, base, tool)


def _geometry_of(table: DHTable) -> LegGeometry:
    frames = dh_frames(table, np.zeros(3))
    foot = forward_kinematics_dh(table, np.zeros(3))
    return LegGeometry(frames[:3, :3, 3], frames[:3, :3, 2], foot, table.lower_limits,
                       table.upper_limits)


def test_real_leg_dh_table_matches_thesis_table_1():
    theta_deg, d, alpha_deg, a = np.array(TABLE.dh_rows_degrees()).T
    report = (f"derived DH table:\n{format_dh_table(TABLE)}\n"
              f"base=\n{TABLE.base}\ntool=\n{TABLE.tool}")
    assert abs(abs(alpha_deg[0]) - 90.0) < 1e-9, report
    assert np.allclose(alpha_deg[1:], 0.0, atol=1e-9), report
    assert np.allclose(d[1:], 0.0, atol=1e-12), report
    assert a[1] == pytest.approx(0.174, abs=1e-12), report
    assert a[2] == pytest.approx(0.152 + 0.135, abs=1e-12), report
    assert abs(d[0]) == pytest.approx(0.025, abs=1e-12), report
    assert a[0] == pytest.approx(0.1462, abs=1e-12), report
    assert np.allclose(theta_deg, 0.0, atol=1e-9), report
    assert np.allclose(TABLE.tool, np.eye(4), atol=1e-12), report
    assert np.allclose(TABLE.base, np.eye(4), atol=1e-12), report
    assert "alpha [deg]" in format_dh_table(TABLE)


def test_dh_forward_kinematics_matches_mujoco_on_the_real_leg():
    angles = _random_angles(np.random.default_rng(1), 500)
    difference = forward_kinematics_dh(TABLE, angles) - mujoco_feet(GEOMETRY, angles)
    assert np.max(np.abs(difference)) < 1e-12
    single = angles[0]
    assert forward_kinematics_dh(TABLE, single).shape == (3,)
    frames = dh_frames(TABLE, angles)
    assert np.allclose(frames[7, 3] @ TABLE.tool[:, 3],
                       np.append(mujoco_feet(GEOMETRY, angles[7]), 1.0), atol=1e-12)
    # frame i-1 turns about joint i: its z axis is MuJoCo's joint axis, its origin on it
    anchors, axes = mujoco_joint_axes(GEOMETRY, angles[7])
    for joint in range(3):
        z_axis, origin = frames[7, joint, :3, 2], frames[7, joint, :3, 3]
        assert np.allclose(z_axis, axes[joint], atol=1e-12)
        assert np.linalg.norm(np.cross(origin - anchors[joint], z_axis)) < 1e-12


@pytest.mark.parametrize("seed", range(25))
def test_rederived_table_of_a_synthetic_chain_gives_the_same_kinematics(seed):
    generator = np.random.default_rng(100 + seed)
    table = _random_table(generator, table1_structure=False)
    geometry = _geometry_of(table)
    derived = dh_from_geometry(geometry)
    angles = generator.uniform(-np.pi, np.pi, size=(50, 3))
    expected = forward_kinematics_dh(table, angles)
    assert np.max(np.abs(forward_kinematics_dh(derived, angles) - expected)) < 1e-12
    assert np.max(np.abs(mujoco_feet(geometry, angles) - expected)) < 1e-12
    assert np.allclose(derived.tool[:3, :3], np.eye(3)) and np.allclose(derived.tool[:2, 3], 0)


def test_inverse_kinematics_round_trip_on_the_real_leg():
    for angles in _random_angles(np.random.default_rng(2), 200):
        target = mujoco_feet(GEOMETRY, angles)
        result = inverse_kinematics(GEOMETRY, target)
        assert result.reachable
        assert result.error < 1e-9
        assert np.linalg.norm(mujoco_feet(GEOMETRY, result.angles) - target) < 1e-9
        assert np.all(result.angles >= GEOMETRY.lower_limits)
        assert np.all(result.angles <= GEOMETRY.upper_limits)
        assert np.allclose(result.angles, angles, atol=1e-7)  # unique in-limit solution


@pytest.mark.parametrize("seed", range(10))
def test_inverse_kinematics_round_trip_on_synthetic_table_1_chains(seed):
    generator = np.random.default_rng(300 + seed)
    table = _random_table(generator, table1_structure=True)
    geometry = _geometry_of(table)
    for angles in generator.uniform(-np.pi, np.pi, size=(20, 3)):
        target = forward_kinematics_dh(table, angles)
        for model in (table, geometry):
            result = inverse_kinematics(model, target, current_angles=angles)
            assert result.reachable and result.error < 1e-9
            assert np.linalg.norm(forward_kinematics_dh(table, result.angles) - target) < 1e-9


def test_branch_selection_follows_the_current_angles():
    wide = real_leg_geometry([-170.0] * 3, [170.0] * 3)
    angles = np.array([0.3, -0.5, 0.8])
    a2, a3 = TABLE.a[1], TABLE.a[2]
    planar = np.arctan2(a2 * np.sin(angles[1]) + a3 * np.sin(angles[1] + angles[2]),
                        a2 * np.cos(angles[1]) + a3 * np.cos(angles[1] + angles[2]))
    flipped = np.array([angles[0], 2 * planar - angles[1], -angles[2]])  # other elbow branch
    target = mujoco_feet(wide, angles)
    assert np.linalg.norm(mujoco_feet(wide, flipped) - target) < 1e-12
    for branch in (angles, flipped):
        result = inverse_kinematics(wide, target, current_angles=branch + 0.05)
        assert np.allclose(result.angles, branch, atol=1e-9)
    first = inverse_kinematics(wide, target).angles
    assert np.allclose(first, inverse_kinematics(wide, target).angles)


def _millimetre_distance(message: str) -> float:
    return float(re.search(r"is (\d+\.\d) mm away", message).group(1))


def test_far_target_is_outside_the_workspace():
    target = np.array([2.0, 0.0, 0.0])
    with pytest.raises(UnreachableTargetError) as caught:
        inverse_kinematics(GEOMETRY, target)
    message = str(caught.value)
    assert "(2000.0, 0.0, 0.0) mm" in message and "outside workspace" in message
    nearest = inverse_kinematics(GEOMETRY, target, clamp=True)
    assert _millimetre_distance(message) == pytest.approx(1000 * nearest.error, abs=0.051)
    assert isinstance(caught.value, ValueError)


@pytest.mark.parametrize(
    ("angles_deg", "joint", "words"),
    [((120.0, -30.0, 50.0), "alpha", "upper limit 90.0 deg"),
     ((0.0, -30.0, 5.0), "gamma", "lower limit 17.0 deg"),
     ((10.0, 20.0, 40.0), "beta", "upper limit -1.0 deg")],
)
def test_target_blocked_by_a_joint_limit_names_the_limit(angles_deg, joint, words):
    target = mujoco_feet(GEOMETRY, np.radians(angles_deg))
    assert np.linalg.norm(target) < np.sum(TABLE.a)  # inside the reach sphere
    with pytest.raises(UnreachableTargetError) as caught:
        inverse_kinematics(GEOMETRY, target)
    message = str(caught.value)
    assert "blocked by joint limits" in message and f"{joint} " in message and words in message
    assert _millimetre_distance(message) > 0.0
    assert joint in JOINT_NAMES


@pytest.mark.parametrize(
    "target",
    [mujoco_feet(GEOMETRY, np.radians([120.0, -30.0, 50.0])),
     mujoco_feet(GEOMETRY, np.radians([0.0, -30.0, 5.0])),
     np.array([0.05, 0.02, -0.1]), np.array([2.0, -1.0, 0.5])],
)
def test_clamped_solution_is_in_limits_and_no_worse_than_sampled_configurations(target):
    result = inverse_kinematics(GEOMETRY, target, clamp=True, current_angles=np.zeros(3))
    assert not result.reachable
    assert np.all(result.angles >= GEOMETRY.lower_limits)
    assert np.all(result.angles <= GEOMETRY.upper_limits)
    assert result.error == pytest.approx(np.linalg.norm(result.foot - target), abs=1e-15)
    samples = _random_angles(np.random.default_rng(3), 2000)
    sampled = np.linalg.norm(mujoco_feet(GEOMETRY, samples) - target, axis=-1)
    assert result.error <= sampled.min() + 1e-12


@pytest.mark.parametrize("model", [TABLE, GEOMETRY], ids=["table", "geometry"])
def test_jacobian_matches_finite_differences(model):
    angles = _random_angles(np.random.default_rng(4), 20)
    jacobian = foot_jacobian(model, angles)
    step = 1e-6
    for joint in range(3):
        shift = np.zeros(3)
        shift[joint] = step
        column = (mujoco_feet(GEOMETRY, angles + shift)
                  - mujoco_feet(GEOMETRY, angles - shift)) / (2 * step)
        assert np.max(np.abs(jacobian[..., joint] - column)) < 1e-6
    assert foot_jacobian(model, angles[0]).shape == (3, 3)


@pytest.mark.parametrize("seed", range(5))
def test_single_leg_and_batched_kinematics_are_the_same_chain(seed):
    # one compiled DH chain serves one set of angles, a batch of any shape and the frames
    generator = np.random.default_rng(200 + seed)
    table = _random_table(generator, table1_structure=seed % 2 == 0)
    angles = generator.uniform(-np.pi, np.pi, size=(4, 5, 3))
    batch_feet = forward_kinematics_dh(table, angles)
    batch_jacobians = foot_jacobian(table, angles)
    frames = dh_frames(table, angles)
    assert batch_feet.shape == (4, 5, 3) and batch_jacobians.shape == (4, 5, 3, 3)
    for k in np.ndindex(4, 5):
        np.testing.assert_array_equal(forward_kinematics_dh(table, angles[k]), batch_feet[k])
        np.testing.assert_array_equal(foot_jacobian(table, angles[k]), batch_jacobians[k])
        np.testing.assert_array_equal(dh_frames(table, angles[k]), frames[k])
        assert np.allclose((frames[k][3] @ table.tool[:, 3])[:3], batch_feet[k], atol=1e-15)


def test_invalid_geometry_is_rejected_with_clear_messages():
    good = {"joint_points": np.zeros((3, 3)), "joint_axes": np.eye(3),
            "foot_point": np.ones(3), "lower_limits": -np.ones(3), "upper_limits": np.ones(3)}
    LegGeometry(**good)
    with pytest.raises(ValueError, match="unit vectors"):
        LegGeometry(**{**good, "joint_axes": 2 * np.eye(3)})
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        LegGeometry(**{**good, "foot_point": np.ones(2)})
    with pytest.raises(ValueError, match="joint beta: lower limit"):
        LegGeometry(**{**good, "lower_limits": [0.0, 2.0, 0.0]})
    odd = DHTable([0, 0, 0], [0, 0, 0], [0.3, 0, 0], [0.1, 0.1, 0.1])
    with pytest.raises(ValueError, match="Table-1 structure"):
        inverse_kinematics(odd, [0.1, 0.0, 0.0])
