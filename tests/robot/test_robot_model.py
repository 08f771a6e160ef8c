"""Tests of the robot's MuJoCo model as built from ``crr-quadruped`` (no stepping).

Each test checks a physical relation against an independent closed form: capsule masses
(SrLib ``UpdateInertia(density)``, App. C.2.1), the pin-to-pin length and the torque of a
cylinder force (thesis eq 5.2.1-5.2.9, written out again here), the DH forward kinematics
(Table 1) against MuJoCo's foot site, and the parameter checks of the robot file.
"""

from __future__ import annotations

import math
import tomllib

import mujoco
import numpy as np
import pytest
import tomli_w

from pneumaquad.params import DATA_DIR, ParameterError, load_robot
from pneumaquad.robot.builder import build_robot
from pneumaquad.robot.legs import leg_dh_table, thorax_frame_points
from pneumaquad.robot.linkage import moment_arm, pin_length, piston_position

IN = 0.0254
JOINTS = ("alpha", "beta", "gamma")
#: Cylinder strokes of the robot's joints, App. C.1.1 (crr-alpha l.55, beta l.67, gamma l.80).
STROKES_IN = {"alpha": 3.75, "beta": 1.75, "gamma": 1.75}


@pytest.fixture(scope="module")
def params():
    return load_robot("crr-quadruped")


@pytest.fixture(scope="module")
def fixed(params):
    return build_robot(params, "fixed")


@pytest.fixture(scope="module")
def quadruped(params):
    return build_robot(params, "quadruped")


def _body(model, name: str) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)


def _capsule_mass(link) -> float:
    """ρ (π r² L + 4/3 π r³): SrLib's capsule of the listed length (App. C.2.1)."""
    r = link.diameter / 2
    return link.density * (math.pi * r * r * link.length + 4.0 / 3.0 * math.pi * r**3)


def _random_angles(robot, generator, count):
    return generator.uniform(
        robot.lower_limits(), robot.upper_limits(), size=(count, robot.joint_count)
    )


# --- 1. masses and inertias -------------------------------------------------------------
def test_link_masses_follow_the_capsule_formula(fixed, params):
    model = fixed.model
    coxa = _capsule_mass(params.coxa1) + _capsule_mass(params.coxa2)  # two welded capsules
    for leg in fixed.legs:
        assert model.body_mass[_body(model, f"{leg}_coxa")] == pytest.approx(coxa, rel=1e-12)
        for link in ("femur", "tibia"):
            expected = _capsule_mass(getattr(params, link))
            assert model.body_mass[_body(model, f"{leg}_{link}")] == pytest.approx(
                expected, rel=1e-12
            )
    # App. C.2.1 numbers: femur 700 kg/m³, Ø 50 mm x 123 mm; tibia aluminium Ø 15 x 255 mm.
    assert model.body_mass[_body(model, "front_right_femur")] == pytest.approx(0.21487, abs=1e-5)
    assert model.body_mass[_body(model, "front_right_tibia")] == pytest.approx(0.12644, abs=1e-5)


def test_thorax_mass_override_is_applied(fixed, params):
    thorax = fixed.model.body_mass[fixed.thorax_id]
    assert params.thorax.mass is not None
    assert thorax == pytest.approx(params.thorax.mass, rel=1e-12)
    # The listing's density would give 56 kg (C.2.2 l.26); the override replaces it.
    assert _capsule_mass(params.thorax) == pytest.approx(56.0, rel=0.01)
    assert thorax < 0.5 * _capsule_mass(params.thorax)
    heavier = build_robot(load_robot("crr-quadruped", ['thorax.mass="3.5 kg"']), "fixed")
    assert heavier.model.body_mass[heavier.thorax_id] == pytest.approx(3.5, rel=1e-12)


def test_femur_inertia_override_reaches_the_model(params):
    moments = (0.001, 0.002, 0.003)
    override = 'femur.inertia=["0.001 kg*m^2", "0.002 kg*m^2", "0.003 kg*m^2"]'
    robot = build_robot(load_robot("crr-quadruped", [override]), "fixed")
    model = robot.model
    for leg in robot.legs:
        femur = _body(model, f"{leg}_femur")
        assert np.allclose(model.body_inertia[femur], moments, rtol=1e-12)
        assert model.body_mass[femur] == pytest.approx(_capsule_mass(params.femur), rel=1e-12)
        assert np.allclose(model.body_ipos[femur], 0.0)  # about the link frame (schema doc)
        # the tibia keeps its capsule inertia
        tibia = _body(model, f"{leg}_tibia")
        assert not np.allclose(model.body_inertia[tibia], moments)


def test_coxa_inertia_override_keeps_the_coxa_mass(params):
    override = 'coxa1.inertia=["0.001 kg*m^2", "0.001 kg*m^2", "0.0005 kg*m^2"]'
    robot = build_robot(load_robot("crr-quadruped", [override]), "fixed")
    coxa = _body(robot.model, "front_right_coxa")
    expected = _capsule_mass(params.coxa1) + _capsule_mass(params.coxa2)
    assert robot.model.body_mass[coxa] == pytest.approx(expected, rel=1e-12)
    assert np.allclose(robot.model.body_inertia[coxa], [0.001, 0.001, 0.0005])


def test_tendon_armature_is_the_moving_piston_mass(fixed, params):
    for i, joint_type in enumerate(fixed.joint_types):
        assert fixed.model.tendon_armature[fixed.tendon_id[i]] == pytest.approx(
            params.linkages[joint_type].moving_mass, rel=1e-12
        )


# --- 2. cylinder length and stroke ------------------------------------------------------
def _law_of_cosines(linkage, theta):
    """Pin-to-pin length l2 + x of eq 5.2.1/5.2.3/5.2.5, γ = γ0 ± θ (eq 5.2.2/5.2.4/5.2.6)."""
    l1, l3 = linkage.child_pivot_radius, linkage.parent_pivot_radius
    gamma = linkage.included_angle_at_zero + linkage.direction * theta
    return math.sqrt(l1 * l1 + l3 * l3 - 2.0 * l1 * l3 * math.cos(gamma)), gamma


def test_tendon_length_is_the_pin_length_at_random_angles(fixed):
    model, data = fixed.model, mujoco.MjData(fixed.model)
    for angles in _random_angles(fixed, np.random.default_rng(7), 50):
        data.qpos[fixed.qpos_address] = angles
        mujoco.mj_forward(model, data)
        for i, joint_type in enumerate(fixed.joint_types):
            linkage = fixed.linkages[joint_type]
            length = data.ten_length[fixed.tendon_id[i]]
            assert abs(length - pin_length(linkage, angles[i])) < 1e-12
            assert abs(length - _law_of_cosines(linkage, angles[i])[0]) < 1e-12


@pytest.mark.parametrize("joint_type", JOINTS)
def test_piston_spans_the_stroke_exactly_between_the_joint_limits(fixed, joint_type):
    stroke = fixed.actuators[joint_type].cylinder.stroke
    assert stroke == pytest.approx(STROKES_IN[joint_type] * IN, rel=1e-12)
    linkage = fixed.linkages[joint_type]
    joint = getattr(fixed.parameters.leg, joint_type)
    ends = sorted(
        [piston_position(linkage, joint.lower_limit), piston_position(linkage, joint.upper_limit)]
    )
    assert ends[0] == pytest.approx(0.0, abs=1e-12)
    assert ends[1] == pytest.approx(stroke, abs=1e-12)
    # x is monotonic in θ inside the range (γ stays within (0, π)), so the stroke is the span
    inside = piston_position(linkage, np.linspace(joint.lower_limit, joint.upper_limit, 201))
    assert np.all(np.diff(inside) * linkage.direction > 0)
    assert inside.min() >= -1e-12 and inside.max() <= stroke + 1e-12
    # and the same in MuJoCo: tendon length - l2 at the limits of the front-right joint
    i = fixed.joint_names.index(f"front_right_{joint_type}")
    data = mujoco.MjData(fixed.model)
    measured = []
    for limit in (joint.lower_limit, joint.upper_limit):
        data.qpos[fixed.qpos_address[i]] = limit
        mujoco.mj_forward(fixed.model, data)
        measured.append(data.ten_length[fixed.tendon_id[i]] - linkage.retracted_length)
    assert sorted(measured) == pytest.approx([0.0, stroke], abs=1e-12)


# --- 3. virtual work --------------------------------------------------------------------
def test_unit_cylinder_force_gives_the_moment_arm_torque(fixed):
    model, data = fixed.model, mujoco.MjData(fixed.model)
    generator = np.random.default_rng(11)
    angles = _random_angles(fixed, generator, 1)[0]
    rates = generator.normal(scale=2.0, size=fixed.joint_count)
    data.qpos[fixed.qpos_address] = angles
    data.qvel[fixed.dof_address] = rates
    for i, joint_type in enumerate(fixed.joint_types):
        linkage = fixed.linkages[joint_type]
        data.ctrl[:] = 0.0
        data.ctrl[fixed.actuator_id[i]] = 1.0  # 1 N extending the cylinder
        mujoco.mj_forward(model, data)
        torque = data.qfrc_actuator[fixed.dof_address[i]]
        # eq 5.2.7-5.2.9: T = l3 F l1 sin γ / (l2 + x), signed by dγ/dθ = s
        length, gamma = _law_of_cosines(linkage, angles[i])
        thesis = (
            linkage.direction
            * linkage.parent_pivot_radius
            * linkage.child_pivot_radius
            * math.sin(gamma)
            / length
        )
        assert abs(torque - moment_arm(linkage, angles[i])) < 1e-10
        assert abs(torque - thesis) < 1e-10
        others = np.delete(data.qfrc_actuator, fixed.dof_address[i])
        assert np.max(np.abs(others)) < 1e-10  # a cylinder only loads its own joint
        # power: τ θ̇ = F ẋ, with ẋ = MuJoCo's tendon velocity
        power_joint = torque * rates[i]
        power_cylinder = 1.0 * data.ten_velocity[fixed.tendon_id[i]]
        assert abs(power_joint - power_cylinder) < 1e-10
        assert data.actuator_force[fixed.actuator_id[i]] == pytest.approx(1.0)


# --- 4. kinematics ----------------------------------------------------------------------
def test_dh_forward_kinematics_matches_the_mujoco_foot_site(quadruped):
    model, data = quadruped.model, mujoco.MjData(quadruped.model)
    generator = np.random.default_rng(5)
    tables = {leg: leg_dh_table(quadruped, leg) for leg in quadruped.legs}
    worst = 0.0
    for angles in _random_angles(quadruped, generator, 30):
        # the thorax anywhere, any orientation: FK is in the thorax frame
        data.qpos[0:3] = generator.normal(size=3)
        quaternion = generator.normal(size=4)
        data.qpos[3:7] = quaternion / np.linalg.norm(quaternion)
        data.qpos[quadruped.qpos_address] = angles
        mujoco.mj_forward(model, data)
        rotation = data.xmat[quadruped.thorax_id].reshape(3, 3)
        origin = data.xpos[quadruped.thorax_id]
        for j, leg in enumerate(quadruped.legs):
            foot = rotation.T @ (data.site_xpos[quadruped.foot_site_id[j]] - origin)
            dh = thorax_frame_points(tables[leg], angles[3 * j : 3 * j + 3])
            worst = max(worst, float(np.max(np.abs(dh - foot))))
    assert worst < 1e-12


def test_front_right_dh_table_has_the_table_1_structure(fixed):
    theta, d, alpha, a = np.array(leg_dh_table(fixed, "front_right").dh_rows_degrees()).T
    assert abs(abs(alpha[0]) - 90.0) < 1e-9
    assert np.allclose(alpha[1:], 0.0, atol=1e-9)
    assert np.allclose(d[1:], 0.0, atol=1e-12)
    assert a[1] == pytest.approx(0.174, abs=1e-12)  # femur: 0.087 + 0.087 (C.2.1 l.66-74)
    assert a[2] == pytest.approx(0.287, abs=1e-12)  # tibia: 0.152 + 0.255/2 + 0.015/2
    assert np.allclose(theta, 0.0, atol=1e-9)


def test_legs_are_mirror_and_fore_aft_images(fixed):
    """Left/right mounts mirror each other (C.2.2), so all four tables are equal up to α1."""
    rows = {leg: np.array(leg_dh_table(fixed, leg).dh_rows_degrees()) for leg in fixed.legs}
    for leg in fixed.legs:
        assert np.allclose(np.abs(rows[leg]), np.abs(rows["front_right"]), atol=1e-9)


# --- 5. configurations and environments -------------------------------------------------
def _joint_types(model):
    return [int(t) for t in model.jnt_type]


def test_configurations_have_the_expected_joints(params, fixed, quadruped):
    free, hinge = int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_HINGE)
    assert fixed.model.nq == 12 and fixed.model.nv == 12
    assert free not in _joint_types(fixed.model) and not fixed.free
    assert quadruped.model.nq == 19 and quadruped.model.nv == 18
    assert _joint_types(quadruped.model).count(free) == 1 and quadruped.free
    for robot in (fixed, quadruped):
        assert robot.joint_count == 12 and robot.model.nu == 12 and robot.model.ntendon == 12
    testbed = build_robot(params, "testbed")
    types = _joint_types(testbed.model)
    assert types.count(free) == 1 and types.count(hinge) == 8  # 6 leg joints + 2 wheels
    assert testbed.legs == ("front_left", "front_right")
    assert testbed.joint_count == 6 and testbed.model.nu == 6
    assert testbed.model.nq == 7 + 6 + 2
    wheels = [
        testbed.model.joint(i).name
        for i in range(testbed.model.njnt)
        if testbed.model.joint(i).name.startswith("testbed_")
    ]
    assert sorted(wheels) == ["testbed_left_wheel", "testbed_right_wheel"]
    with pytest.raises(ValueError, match="configuration"):
        build_robot(params, "tripod")


def _world_geoms(model) -> dict[str, int]:
    return {model.geom(g).name: g for g in range(model.ngeom) if model.geom_bodyid[g] == 0}


def test_environments_add_their_obstacles(params):
    box = int(mujoco.mjtGeom.mjGEOM_BOX)
    env = params.environment
    flat = build_robot(params, "fixed", "flat").model
    assert list(_world_geoms(flat)) == ["ground"]

    block = build_robot(params, "fixed", "block").model
    geoms = _world_geoms(block)
    assert sorted(geoms) == ["block", "ground"]
    assert block.geom_type[geoms["block"]] == box
    assert np.allclose(2 * block.geom_size[geoms["block"]], env.block_size)
    assert block.geom_pos[geoms["block"]][2] == pytest.approx(env.block_size[2] / 2)  # on ground

    ramp = build_robot(params, "fixed", "ramp").model
    geoms = _world_geoms(ramp)
    assert sorted(geoms) == ["ground", "ramp"]
    g = geoms["ramp"]
    assert ramp.geom_type[g] == box and np.allclose(2 * ramp.geom_size[g], env.ramp_size)
    data = mujoco.MjData(ramp)
    mujoco.mj_forward(ramp, data)
    rotation = data.geom_xmat[g].reshape(3, 3)
    tilt = math.acos(float(rotation[2, 2]))  # plate normal against the vertical
    assert tilt == pytest.approx(env.ramp_slope, abs=1e-9)
    half = ramp.geom_size[g]
    lower_back_edge = data.geom_xpos[g] + rotation @ np.array([-half[0], 0.0, -half[2]])
    assert lower_back_edge[0] == pytest.approx(env.ramp_position[0], abs=1e-9)
    assert lower_back_edge[2] == pytest.approx(0.0, abs=1e-9)  # lower edge on the ground


def _rough_field(params, seed: int) -> np.ndarray:
    model = build_robot(params, "fixed", "rough", seed=seed).model
    rows = [
        np.concatenate([model.geom_pos[g], model.geom_size[g]])
        for name, g in _world_geoms(model).items()
        if name.startswith("rough_")
    ]
    return np.array(rows)


def test_rough_field_is_seeded(params):
    env = params.environment
    first = _rough_field(params, 3)
    cells = round(env.rough_size[0] / env.rough_cell) * round(env.rough_size[1] / env.rough_cell)
    assert 0.3 * cells < len(first) < 0.7 * cells  # "HALF RANDOM": about half raised
    heights = 2 * first[:, 5]
    assert np.all(heights > 0) and np.all(heights <= env.rough_max_height + 1e-12)
    assert np.allclose(first[:, 2], heights / 2)  # standing on the ground
    assert np.array_equal(first, _rough_field(params, 3))
    other = _rough_field(params, 4)
    assert first.shape != other.shape or not np.array_equal(first, other)


# --- 6. MJCF export ---------------------------------------------------------------------
@pytest.mark.parametrize(
    ("configuration", "environment"),
    [("quadruped", "flat"), ("testbed", "ramp"), ("fixed", "rough")],
)
def test_mjcf_export_compiles_to_the_same_model(params, configuration, environment):
    robot = build_robot(params, configuration, environment)
    again = mujoco.MjModel.from_xml_string(robot.to_xml())
    m = robot.model
    for count in ("nbody", "njnt", "nq", "ngeom", "ntendon", "nu", "nsite"):
        assert getattr(again, count) == getattr(m, count), count
    # MuJoCo writes 6 significant digits: masses agree to that, not to the last bit
    assert np.allclose(again.body_mass, m.body_mass, rtol=1e-5, atol=0)
    assert np.allclose(again.body_inertia, m.body_inertia, rtol=1e-4, atol=1e-9)
    assert np.allclose(again.tendon_armature, m.tendon_armature, rtol=1e-5)
    # the cylinders keep their length law to a micrometre (0.003 % of the 1.75 in stroke)
    data, data_again = mujoco.MjData(m), mujoco.MjData(again)
    angles = _random_angles(robot, np.random.default_rng(2), 1)[0]
    for d in (data, data_again):
        d.qpos[robot.qpos_address] = angles
        mujoco.mj_forward(m if d is data else again, d)
    assert np.max(np.abs(data_again.ten_length - data.ten_length)) < 2e-6


# --- 7. parameter errors ----------------------------------------------------------------
def test_wrong_unit_is_reported_with_its_key():
    with pytest.raises(ParameterError) as caught:
        load_robot("crr-quadruped", ['leg.beta.lower_limit="10 kg"'])
    assert [p.key for p in caught.value.problems] == ["leg.beta.lower_limit"]
    assert "leg.beta.lower_limit" in str(caught.value)
    assert "angle" in str(caught.value)


def test_missing_mount_is_reported_with_its_key(tmp_path):
    with (DATA_DIR / "crr-quadruped.toml").open("rb") as f:
        raw = tomllib.load(f)
    del raw["mounts"]["rear_left"]
    path = tmp_path / "three-legs.toml"
    path.write_text(tomli_w.dumps(raw))
    with pytest.raises(ParameterError) as caught:
        load_robot(path)
    keys = [p.key for p in caught.value.problems]
    assert "mounts.rear_left" in keys
    assert "mounts.rear_left" in str(caught.value)


def test_joint_range_beyond_half_a_turn_is_rejected():
    with pytest.raises(ParameterError) as caught:
        load_robot("crr-quadruped", ['leg.gamma.upper_limit="200 deg"'])
    assert "leg.gamma.upper_limit" in [p.key for p in caught.value.problems]


# --- 8. MuJoCo options ------------------------------------------------------------------
def test_shipped_mujoco_options_reach_the_model(quadruped):
    opt = quadruped.model.opt
    assert opt.solver == mujoco.mjtSolver.mjSOL_NEWTON
    assert opt.iterations == 50
    assert opt.tolerance == 1e-8
    assert opt.noslip_iterations == 0
    assert opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert opt.impratio == 10.0
    assert opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert opt.disableflags & mujoco.mjtDisableBit.mjDSBL_AUTORESET
    # the shipped file turns MuJoCo's island discovery off (docs/benchmarks.md)
    assert opt.disableflags & mujoco.mjtDisableBit.mjDSBL_ISLAND


@pytest.mark.parametrize(
    ("override", "option", "expected"),
    [
        ("simulation.solver=cg", "solver", mujoco.mjtSolver.mjSOL_CG),
        ("simulation.solver=pgs", "solver", mujoco.mjtSolver.mjSOL_PGS),
        ("simulation.solver_iterations=7", "iterations", 7),
        ("simulation.solver_tolerance=1e-5", "tolerance", 1e-5),
        ("simulation.noslip_iterations=3", "noslip_iterations", 3),
        ("contact.friction_cone=pyramidal", "cone", mujoco.mjtCone.mjCONE_PYRAMIDAL),
        ("contact.friction_impedance_ratio=2.5", "impratio", 2.5),
        ("simulation.integrator=euler", "integrator", mujoco.mjtIntegrator.mjINT_EULER),
    ],
)
def test_mujoco_option_overrides_reach_the_model_and_its_export(override, option, expected):
    robot = build_robot(load_robot("crr-quadruped", [override]), "fixed")
    again = mujoco.MjModel.from_xml_string(robot.to_xml())
    assert getattr(robot.model.opt, option) == expected
    assert getattr(again.opt, option) == expected


@pytest.mark.parametrize("islands", [True, False])
def test_constraint_islands_set_mujocos_island_flag(islands):
    robot = build_robot(
        load_robot("crr-quadruped", [f"simulation.constraint_islands={str(islands).lower()}"]),
        "fixed")
    island = mujoco.mjtDisableBit.mjDSBL_ISLAND
    for model in (robot.model, mujoco.MjModel.from_xml_string(robot.to_xml())):
        assert bool(model.opt.disableflags & island) is not islands
        assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_AUTORESET


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("simulation.solver=newtonian", "simulation.solver"),
        ("simulation.solver_tolerance=-1e-3", "simulation.solver_tolerance"),
        ("contact.friction_cone=round", "contact.friction_cone"),
        ("simulation.constraint_islands=0", "simulation.constraint_islands"),
    ],
)
def test_mujoco_option_out_of_range_is_reported_with_its_key(override, key):
    with pytest.raises(ParameterError) as caught:
        load_robot("crr-quadruped", [override])
    assert [p.key for p in caught.value.problems] == [key]


def test_piston_mass_on_the_joint_is_its_mean_reflected_inertia(params):
    robot = build_robot(load_robot("crr-quadruped", ["simulation.piston_inertia=joint"]), "fixed")
    model = robot.model
    assert np.all(model.tendon_armature == 0.0)
    for i, joint_type in enumerate(robot.joint_types):
        linkage, joint = robot.linkages[joint_type], getattr(params.leg, joint_type)
        theta = np.linspace(joint.lower_limit, joint.upper_limit, 20001)
        lengths = np.array([_law_of_cosines(linkage, t)[0] for t in theta])
        arm = np.gradient(lengths, theta)  # dx/dθ: the moment arm of eq 5.2.7-5.2.9
        mean_square = np.trapezoid(arm**2, theta) / (theta[-1] - theta[0])
        expected = params.linkages[joint_type].moving_mass * mean_square
        assert model.dof_armature[robot.dof_address[i]] == pytest.approx(expected, rel=1e-5)
