"""The Gymnasium environment of the quadruped (pneumaquad.interop, docs/gymnasium.md)."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pneumaquad.interop as interop
from pneumaquad.interop import QuadrupedEnv, RandomPolicy, observation_slices
from pneumaquad.interop.gym_terms import OBSERVATION_LAYOUT, has_fallen, observation_size
from pneumaquad.robot.frames import euler_zyx_matrix, rotation_to_quaternion
from pneumaquad.robot.simulation import SimulationDivergedError

SLICES = observation_slices()
#: What check_env says of every continuous-control environment with SI units; advice only.
ADVISORY = ("symmetric and normalized space", "minimum value is -infinity",
            "maximum value is infinity")


def _episode(env: QuadrupedEnv, seed: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Observations (steps + 1, 62) and rewards (steps,) under seeded random joint
    references within ±0.15 rad of the initial pose (wide random references knock the
    robot over within a second)."""
    observation, _ = env.reset(seed=seed)
    generator = np.random.default_rng(seed)
    observations, rewards = [observation], []
    for _ in range(steps):
        action = env.initial_angles + generator.uniform(-0.15, 0.15, 12)
        observation, reward, terminated, truncated, _ = env.step(action)
        observations.append(observation)
        rewards.append(reward)
        assert not (terminated or truncated)
    return np.array(observations), np.array(rewards)


def test_importing_registers_the_id_without_loading_mujoco_or_numba() -> None:
    assert interop.ENV_ID == "pneumaquad/Quadruped-v0"
    assert interop.ENV_ID in gymnasium.registry
    code = ("import sys, pneumaquad.interop, gymnasium; "
            "assert 'pneumaquad/Quadruped-v0' in gymnasium.registry; "
            "print(sorted(m for m in ('mujoco', 'numba') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == "[]"


def test_gymnasium_make_finds_it_from_the_module_prefixed_id() -> None:
    code = ("import gymnasium; env = gymnasium.make('pneumaquad.interop:pneumaquad/Quadruped-v0'); "
            "print(env.spec.max_episode_steps, env.unwrapped.observation_space.shape)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.split() == ["1000", "(62,)"]


@pytest.mark.parametrize("action", ["angles", "voltage"])
def test_check_env_passes(action: str) -> None:
    env = gymnasium.make(interop.ENV_ID, action=action)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    unexpected = [str(w.message) for w in caught
                  if not any(text in str(w.message) for text in ADVISORY)]
    assert unexpected == []


def test_spaces_are_the_joint_limits_and_valve_ranges() -> None:
    angles = QuadrupedEnv(action="angles", settle_time=0.0)
    robot = angles.sim.robot
    assert angles.action_space.shape == (12,)
    np.testing.assert_array_equal(angles.action_space.low, robot.lower_limits())
    np.testing.assert_array_equal(angles.action_space.high, robot.upper_limits())
    voltage = QuadrupedEnv(action="voltage", settle_time=0.0)
    assert (voltage.action_space.low == 0.0).all() and (voltage.action_space.high == 10.0).all()
    assert angles.observation_space.shape == (observation_size(),) == (62,)
    assert sum(size for _, size, _ in OBSERVATION_LAYOUT) == 62
    assert SLICES["foot normal forces"].stop == 62


def test_the_first_observation_is_the_robot_standing() -> None:
    env = QuadrupedEnv()
    observation, info = env.reset(seed=0)
    assert env.observation_space.contains(observation)
    assert info["time [s]"] == pytest.approx(0.5)
    np.testing.assert_allclose(observation[SLICES["joint angles"]], env.initial_angles,
                               atol=math.radians(3.0))
    assert 0.3 < observation[SLICES["thorax height"]][0] < 0.45
    assert np.all(np.abs(observation[SLICES["thorax roll pitch yaw"]]) < math.radians(3.0))
    pressures = np.concatenate([observation[SLICES["cap pressures"]],
                                observation[SLICES["rod pressures"]]])
    assert np.all((pressures > 0.09) & (pressures < 0.7))  # MPa absolute
    weight = float(np.sum(env.sim.model.body_mass)) * 9.81
    assert observation[SLICES["foot normal forces"]].sum() == pytest.approx(weight, rel=0.1)


def test_same_seed_gives_bit_identical_episodes() -> None:
    first = _episode(QuadrupedEnv(), seed=7, steps=40)
    again = QuadrupedEnv()
    second = _episode(again, seed=7, steps=40)
    third = _episode(again, seed=7, steps=40)  # the same instance, reset again
    for run in (second, third):
        assert np.array_equal(first[0], run[0]) and np.array_equal(first[1], run[1])


def test_different_seeds_start_differently_and_no_noise_starts_alike() -> None:
    env = QuadrupedEnv()
    one, _ = env.reset(seed=1)
    two, _ = env.reset(seed=2)
    assert not np.array_equal(one, two)
    quiet = QuadrupedEnv(reset_noise=0.0)
    assert np.array_equal(quiet.reset(seed=1)[0], quiet.reset(seed=2)[0])


def test_actions_outside_the_box_are_clipped_into_it() -> None:
    for action_kind in ("angles", "voltage"):
        env, reference = QuadrupedEnv(action=action_kind), QuadrupedEnv(action=action_kind)
        env.reset(seed=3)
        reference.reset(seed=3)
        space = env.action_space
        wild = np.where(np.arange(12) % 2 == 0, space.high + 5.0, space.low - 5.0)
        clipped = np.clip(wild, space.low, space.high)
        observation, reward, *_, info = env.step(wild)
        expected, expected_reward, *_, expected_info = reference.step(clipped)
        assert info["action clipped"] and not expected_info["action clipped"]
        assert np.array_equal(observation, expected) and reward == expected_reward
        mode = 1 if action_kind == "angles" else 2  # closed loop / open loop
        assert (env.sim.control_modes() == mode).all()
        with pytest.raises(ValueError, match="finite"):
            env.step(np.full(12, np.nan))


def test_step_before_reset_is_refused() -> None:
    env = QuadrupedEnv(settle_time=0.0)
    with pytest.raises(RuntimeError, match=r"reset\(\) first"):
        env.step(env.initial_angles)


def test_control_period_option() -> None:
    env = QuadrupedEnv(control_period=0.01, settle_time=0.1)
    env.reset(seed=0)
    env.step(env.initial_angles)
    assert env.steps_per_action == 10
    assert env.sim.time == pytest.approx(0.11)
    assert env.metadata["render_fps"] == pytest.approx(100.0)
    with pytest.raises(ValueError, match="whole number"):
        QuadrupedEnv(control_period=0.0105)
    with pytest.raises(ValueError, match="action"):
        QuadrupedEnv(action="torque")


def test_reward_is_the_documented_formula() -> None:
    env = QuadrupedEnv(lateral_weight=0.3, air_weight=0.2, fall_penalty=4.0)
    env.reset(seed=4)
    previous = {"air consumed [NL]": 0.0}
    for _ in range(100):  # random references: it walks a little, then falls
        _, reward, terminated, _, info = env.step(env.action_space.sample())
        air = info["air consumed [NL]"] - previous["air consumed [NL]"]
        expected = (info["forward progress [m]"] / 0.02 - 0.3 * abs(info["lateral offset [m]"])
                    - 0.2 * air / 0.02 - 4.0 * info["fell"])
        assert reward == pytest.approx(expected, rel=1e-9, abs=1e-12)
        previous = info
        if terminated:
            break
    assert terminated and info["fell"]


def test_a_robot_knocked_over_ends_the_episode_with_the_fall_penalty() -> None:
    env = QuadrupedEnv(fall_penalty=10.0)
    env.reset(seed=0)
    sim = env.sim
    nominal = sim.data.qpos[3:7].copy()
    nominal_matrix = np.zeros(9)
    import mujoco

    mujoco.mju_quat2Mat(nominal_matrix, nominal)
    upside_down = euler_zyx_matrix((0.0, 0.0, math.pi)) @ nominal_matrix.reshape(3, 3)
    sim.set_pose(env.initial_angles, thorax_position=np.array([0.0, 0.0, 0.5]),
                 thorax_quaternion=rotation_to_quaternion(upside_down))
    observation, reward, terminated, truncated, info = env.step(env.initial_angles)
    assert terminated and not truncated and info["fell"]
    assert abs(observation[SLICES["thorax roll pitch yaw"]][0]) > math.radians(150.0)
    assert reward < -9.0
    assert has_fallen(0.1, 0.0, 0.0, 0.15, 0.5) and has_fallen(0.3, 0.0, -0.6, 0.15, 0.5)
    assert has_fallen(math.nan, 0.0, 0.0, 0.15, 0.5)
    assert not has_fallen(0.3, 0.4, -0.4, 0.15, 0.5)


def test_a_diverged_simulation_ends_the_episode(monkeypatch: pytest.MonkeyPatch) -> None:
    env = QuadrupedEnv()
    before, _ = env.reset(seed=0)

    def diverge(count: int = 1, *args: object, **kwargs: object) -> None:
        raise SimulationDivergedError("test", time=1.0)

    monkeypatch.setattr(env.sim, "step", diverge)
    observation, reward, terminated, _, info = env.step(env.initial_angles)
    assert terminated and info["diverged"] and reward == -env.weights.fall
    assert np.array_equal(observation, before)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(env.initial_angles)
    monkeypatch.undo()
    env.reset(seed=0)
    env.step(env.initial_angles)


def test_time_limit_of_the_registration_truncates() -> None:
    env = gymnasium.make(interop.ENV_ID, max_episode_steps=3)
    env.reset(seed=0)
    action = env.unwrapped.initial_angles  # type: ignore[attr-defined]
    flags = [env.step(action)[3] for _ in range(3)]
    assert flags == [False, False, True]


def test_sync_vector_env_steps_copies_that_match_single_envs() -> None:
    vector = gymnasium.make_vec(interop.ENV_ID, num_envs=2, vectorization_mode="sync")
    observations, _ = vector.reset(seed=11)
    assert observations.shape == (2, 62)
    assert not np.array_equal(observations[0], observations[1])  # seeds 11 and 12
    single = QuadrupedEnv()
    for index, seed in enumerate((11, 12)):
        assert np.array_equal(single.reset(seed=seed)[0], observations[index])
    actions = np.tile(single.initial_angles, (2, 1))
    observations, rewards, terminated, truncated, info = vector.step(actions)
    assert observations.shape == (2, 62) and rewards.shape == (2,)
    assert not terminated.any() and not truncated.any()
    assert info["distance [m]"].shape == (2,)
    direct = gymnasium.vector.SyncVectorEnv([lambda: QuadrupedEnv(action="voltage")] * 2)
    assert direct.reset(seed=0)[0].shape == (2, 62)
    direct.step(np.full((2, 12), 5.25))
    vector.close()
    direct.close()


def test_random_policy_is_seeded() -> None:
    space = QuadrupedEnv(settle_time=0.0).action_space
    one, two = RandomPolicy(space, seed=5), RandomPolicy(space, seed=5)
    observation = np.zeros(62)
    for _ in range(3):
        action = one(observation)
        assert space.contains(action)
        assert np.array_equal(action, two(observation))


def test_render_gives_an_rgb_frame_when_a_backend_exists() -> None:
    from pneumaquad.robot.video import RenderingUnavailableError

    env = QuadrupedEnv(render_mode="rgb_array", settle_time=0.0)
    env.reset(seed=0)
    assert QuadrupedEnv(settle_time=0.0).render() is None
    try:
        frame = env.render()
    except RenderingUnavailableError as error:
        pytest.skip(f"no offscreen OpenGL: {error}")
    assert frame is not None and frame.shape == (480, 640, 3) and frame.dtype == np.uint8
    assert frame.std() > 0.0
