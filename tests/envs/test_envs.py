"""The environment suite: registration, the checkers, determinism, vectorisation,
errors, rendering and resources."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import graspenv
from graspenv.envs import GraspEnv

OBS_MODES = ("state", "mask", "goal")


def _make(env_id: str, **kwargs: Any) -> gym.Env[Any, Any]:
    return gym.make(env_id, **kwargs)


def test_six_ids_are_registered() -> None:
    assert len(graspenv.ENV_IDS) == 6
    for env_id in graspenv.ENV_IDS:
        spec = gym.spec(env_id)
        assert spec.max_episode_steps is not None and spec.max_episode_steps > 0


Check = Callable[[gym.Env[Any, Any]], None]


def _gymnasium_checker() -> Check:
    from gymnasium.utils.env_checker import check_env

    return lambda env: check_env(env, skip_render_check=True)


def _sb3_checker() -> Check:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env

    return lambda env: check_env(env, warn=True)


# Imported outside the warnings filter (an import's own warnings are not the env's).
# The unwrapped env: Gymnasium's wrappers do not forward compute_reward (SB3's checker).
@pytest.mark.parametrize("checker", [_gymnasium_checker, _sb3_checker], ids=["gymnasium", "sb3"])
@pytest.mark.parametrize("obs_mode", OBS_MODES)
@pytest.mark.parametrize("env_id", graspenv.ENV_IDS)
def test_checker_passes_without_warnings(
    env_id: str, obs_mode: str, checker: Callable[[], Check]
) -> None:
    check = checker()
    env = _make(env_id, obs_mode=obs_mode)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check(env.unwrapped)
    finally:
        env.close()


def _rollout(env: gym.Env[Any, Any], seed: int, steps: int) -> list[Any]:
    rng = np.random.default_rng(123)
    obs, info = env.reset(seed=seed)
    trace: list[Any] = [obs, info]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(
            env.action_space.sample() * 0 + rng.uniform(-1, 1, env.action_space.shape)
        )
        trace += [obs, reward, terminated, truncated, info]
        if terminated or truncated:
            break
    return trace


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray | np.generic):
        return bool(np.array_equal(a, b))
    return bool(a == b)


@pytest.mark.parametrize("env_id", graspenv.ENV_IDS)
def test_same_seed_and_actions_give_identical_runs(env_id: str) -> None:
    first = _make(env_id, obs_mode="goal")
    second = _make(env_id, obs_mode="goal")
    try:
        a = _rollout(first, seed=7, steps=12)
        b = _rollout(second, seed=7, steps=12)
        # Another episode in between, then the same seed again in one process.
        _rollout(first, seed=8, steps=5)
        c = _rollout(first, seed=7, steps=12)
    finally:
        first.close()
        second.close()
    assert len(a) == len(b) == len(c)
    assert all(_same(x, y) for x, y in zip(a, b, strict=True))
    assert all(_same(x, y) for x, y in zip(a, c, strict=True))


def test_different_seeds_draw_different_episodes() -> None:
    env = _make("graspenv/TurnInPlace-v0")
    try:
        a, _ = env.reset(seed=1)
        b, _ = env.reset(seed=2)
    finally:
        env.close()
    assert not np.array_equal(a, b)


def test_info_has_the_contract_keys() -> None:
    env = _make("graspenv/SqueezeSlide-v0")
    try:
        env.reset(seed=0)
        *_, info = env.step(np.zeros(env.action_space.shape))
    finally:
        env.close()
    for key in (
        "is_success",
        "object_pose",
        "slip",
        "grip_force",
        "n_particles",
        "force_closure",
        "epsilon",
        "tilt",
        "penetration",
    ):
        assert key in info
    assert info["object_pose"].shape == (7,)


def test_compute_reward_is_vectorised_and_matches_step() -> None:
    env = _make("graspenv/TurnInPlace-v0", obs_mode="goal")
    try:
        obs, _ = env.reset(seed=3)
        obs, reward, *_, info = env.step(env.action_space.sample())
        unwrapped = env.unwrapped
        single = unwrapped.compute_reward(obs["achieved_goal"], obs["desired_goal"], info)
        batch = unwrapped.compute_reward(
            np.stack([obs["achieved_goal"]] * 4), np.stack([obs["desired_goal"]] * 4), [info] * 4
        )
    finally:
        env.close()
    assert single == pytest.approx(reward, abs=1e-5)
    assert batch.shape == (4,)
    assert np.allclose(batch, single, atol=1e-5)


def test_bad_actions() -> None:
    env = _make("graspenv/TurnInPlace-v0")
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match="finite"):
            env.step(np.array([np.nan, 0, 0, 0, 0], np.float32))
        with pytest.raises(ValueError, match="shape"):
            env.step(np.zeros(3, np.float32))
        env.step(np.full(5, 7.0, np.float32))  # clipped, not an error
    finally:
        env.close()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"obs_mode": "pixels"}, "obs_mode"),
        ({"proxy": "magic"}, "proxy.method"),
        ({"render_mode": "human"}, "render_mode"),
        ({"fidelity": "ultra"}, "fidelity"),
        ({"config": {"task": {"frame_skp": 2}}}, "task.frame_skp"),
    ],
)
def test_bad_arguments(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        GraspEnv("TurnInPlace", **kwargs)


def test_close_twice() -> None:
    env = _make("graspenv/SidePush-v0")
    env.reset(seed=0)
    env.close()
    env.close()


@pytest.mark.parametrize("proxy", ["persistent", "instant", "rigid"])
def test_every_proxy_reaches_the_env(proxy: str) -> None:
    env = _make("graspenv/SqueezeSlide-v0", proxy=proxy)
    try:
        env.reset(seed=0)
        assert env.unwrapped._sim.config.proxy.method == proxy
        for _ in range(3):
            env.step(env.action_space.sample())
    finally:
        env.close()


@pytest.mark.parametrize("mode", ["rgb_array", "rgb_array_3d"])
def test_render_modes_give_pictures(mode: str) -> None:
    env = _make("graspenv/TurnInPlace-v0", render_mode=mode)
    try:
        env.reset(seed=0)
        env.step(env.action_space.sample())
        picture = env.render()
    finally:
        env.close()
    assert picture is not None and picture.dtype == np.uint8
    assert picture.ndim == 3 and picture.shape[2] == 3
    assert picture.std() > 1.0  # not a blank image


@pytest.mark.parametrize("vectorization_mode", ["sync", "async"])
def test_make_vec(vectorization_mode: str) -> None:
    envs = gym.make_vec(
        "graspenv/TurnInPlace-v0", num_envs=2, vectorization_mode=vectorization_mode
    )
    try:
        obs, _ = envs.reset(seed=0)
        assert obs.shape[0] == 2
        obs, reward, *_ = envs.step(envs.action_space.sample())
        assert reward.shape == (2,)
    finally:
        envs.close()


def test_sb3_subproc_vec_env() -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    # "module:id" makes each worker process import graspenv, which registers the ids.
    envs = make_vec_env(
        "graspenv:graspenv/SqueezeSlide-v0", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv
    )
    try:
        obs = envs.reset()
        assert obs.shape[0] == 2
        envs.step(np.stack([envs.action_space.sample()] * 2))
    finally:
        envs.close()


def _rss_kb() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4


def test_a_thousand_resets_do_not_grow_memory() -> None:
    env = _make("graspenv/TurnInPlace-v0")
    try:
        for seed in range(50):
            env.reset(seed=seed)
        before = _rss_kb()
        for seed in range(1000):
            env.reset(seed=seed)
        after = _rss_kb()
    finally:
        env.close()
    assert after - before < 20_000  # kB


@pytest.mark.parametrize("mode", ["rgb_array", "rgb_array_3d"])
def test_record_video_wraps_both_render_modes(mode: str, tmp_path: Any) -> None:
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(
        _make("graspenv/TurnInPlace-v0", render_mode=mode),
        str(tmp_path / "videos"),  # a folder of its own: RecordVideo warns on one that exists
        episode_trigger=lambda episode: True,
        disable_logger=True,
    )
    try:
        env.reset(seed=0)
        for _ in range(5):
            env.step(env.action_space.sample())
    finally:
        env.close()
    videos = list((tmp_path / "videos").glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000


def test_observation_layout_names_the_state_vector() -> None:
    env = _make("graspenv/SqueezeSlide-v0")
    try:
        obs, _ = env.reset(seed=4)
        layout = env.unwrapped.observation_layout
        position, quaternion = env.unwrapped._sim.object_pose("object")
        goal = env.unwrapped._goal
    finally:
        env.close()
    assert layout["slip"].stop == obs.shape[0]
    assert np.allclose(obs[layout["object_position"]], position, atol=1e-6)
    assert np.allclose(obs[layout["object_quaternion"]], quaternion, atol=1e-6)
    assert np.allclose(obs[layout["goal"]], goal, atol=1e-6)
    assert obs[layout["finger_positions"]].shape == (4,)


@pytest.mark.parametrize("env_id", ["graspenv/TopRub-v0", "graspenv/SqueezeSlide-v0"])
def test_goal_observation_is_the_state_vector_without_the_goal(env_id: str) -> None:
    state_env = _make(env_id)
    goal_env = _make(env_id, obs_mode="goal")
    try:
        state, _ = state_env.reset(seed=2)
        goal, _ = goal_env.reset(seed=2)
        layout = state_env.unwrapped.observation_layout
    finally:
        state_env.close()
        goal_env.close()
    where = layout["goal"]
    assert state.shape == state_env.observation_space.shape
    assert np.array_equal(goal["observation"], np.delete(state, np.arange(where.start, where.stop)))
    assert np.array_equal(goal["desired_goal"], state[where])


def test_render_fps_is_one_picture_per_step() -> None:
    env = GraspEnv("TurnInPlace", config={"task": {"frame_skip": 3}})
    try:
        assert env.metadata["render_fps"] == pytest.approx(1.0 / env.dt)
        assert env.metadata["render_fps"] == pytest.approx(20.0)
    finally:
        env.close()
    assert GraspEnv.metadata["render_fps"] == pytest.approx(30.0)
