"""Every environment trains with stable-baselines3 (tiny budgets; real training is
never part of `make test`)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import graspenv


@pytest.mark.parametrize("algo", ["ppo", "sac"])
@pytest.mark.parametrize("env_id", graspenv.ENV_IDS)
def test_a_few_learning_steps(env_id: str, algo: str) -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO, SAC

    env = gym.make(env_id)
    try:
        if algo == "ppo":
            model = PPO("MlpPolicy", env, n_steps=32, batch_size=16, n_epochs=1, seed=0)
        else:
            model = SAC("MlpPolicy", env, learning_starts=16, batch_size=16, seed=0)
        model.learn(total_timesteps=32)
        obs, _ = env.reset(seed=1)
        action, _ = model.predict(obs, deterministic=True)
    finally:
        env.close()
    assert env.action_space.contains(action.astype(np.float32))


def test_her_with_the_goal_mode() -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import SAC, HerReplayBuffer

    # HER samples only from finished episodes: SqueezeHold's last 70 steps.
    env = gym.make("graspenv/SqueezeHold-v0", obs_mode="goal")
    try:
        model = SAC(
            "MultiInputPolicy",
            env,
            replay_buffer_class=HerReplayBuffer,
            replay_buffer_kwargs={"n_sampled_goal": 2},
            learning_starts=75,
            batch_size=16,
            seed=0,
        )
        model.learn(total_timesteps=85)
    finally:
        env.close()
    assert model.replay_buffer.size() > 0  # type: ignore[union-attr]


def test_cnn_policy_on_masks() -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    env = gym.make("graspenv/TurnInPlace-v0", obs_mode="mask")
    try:
        model = PPO("MultiInputPolicy", env, n_steps=16, batch_size=16, n_epochs=1, seed=0)
        model.learn(total_timesteps=16)
    finally:
        env.close()
    assert model.num_timesteps >= 16
