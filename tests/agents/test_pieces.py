"""Hyperparameter files, the relative-goal wrapper and charts."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from graspenv.plots import bar_chart, line_chart
from graspenv_agents.hyperparams import algorithm_kwargs, default_file, load_hyperparams
from graspenv_agents.wrappers import RelativeGoal


def test_environment_table_overrides_defaults(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")  # the file's keys are checked against SAC's
    path = tmp_path / "sac.toml"
    path.write_text(
        "[defaults]\nbatch_size = 64\ngamma = 0.9\n\n"
        '["graspenv/SqueezeSlide-v0"]\nbatch_size = 128\n'
    )
    slide = load_hyperparams("graspenv/SqueezeSlide-v0", "sac", path)
    turn = load_hyperparams("graspenv/TurnInPlace-v0", "sac", path)
    assert (slide["batch_size"], slide["gamma"]) == (128, 0.9)
    assert (turn["batch_size"], turn["gamma"]) == (64, 0.9)
    assert turn["n_envs"] == 1 and turn["policy"] == "MlpPolicy"  # run settings' defaults


def test_shipped_files_load_for_every_environment() -> None:
    pytest.importorskip("stable_baselines3")  # keys checked against PPO's and SAC's
    import graspenv

    for algo in ("ppo", "sac"):
        assert default_file(algo).is_file()
        for env_id in graspenv.ENV_IDS:
            kwargs = algorithm_kwargs(load_hyperparams(env_id, algo))
            assert "n_timesteps" not in kwargs and "policy_kwargs" in kwargs


def test_activation_names_become_torch_modules() -> None:
    torch = pytest.importorskip("torch")

    kwargs = algorithm_kwargs({"policy_kwargs": {"activation_fn": "tanh"}})
    assert kwargs["policy_kwargs"]["activation_fn"] is torch.nn.Tanh


def test_relative_goal_features_match_the_true_errors() -> None:
    env = RelativeGoal(gym.make("graspenv/TurnInPlace-v0"))
    try:
        obs, _ = env.reset(seed=4)
        base: gym.Env = env.unwrapped  # type: ignore[assignment]
        state = base._state  # type: ignore[attr-defined]
        goal = base._goal  # type: ignore[attr-defined]
        n = env.observation_space.shape[0] - env.env.observation_space.shape[0]
        extra = obs[-n:]
        turn = goal[2] - state.yaw
        assert np.allclose(extra[:2], 10 * (goal[:2] - state.position[:2]), atol=1e-5)
        assert np.allclose(extra[2:4], [math.sin(turn), math.cos(turn)], atol=1e-5)
        assert env.observation_space.contains(obs)
    finally:
        env.close()


def test_relative_goal_needs_state_observations() -> None:
    with pytest.raises(ValueError, match="obs_mode='state'"):
        RelativeGoal(gym.make("graspenv/TurnInPlace-v0", obs_mode="mask"))


def test_charts_draw_their_series(tmp_path: Path) -> None:
    line = line_chart({"s": ([0, 1, 2], [0.0, 0.5, 1.0])}, tmp_path / "l.png", "t", "x", "y")
    bars = bar_chart(
        ["a", "b"], {"one": [0.2, 0.9], "two": [np.nan, 0.4]}, tmp_path / "b.png", "t", "y"
    )
    assert (tmp_path / "l.png").is_file() and (tmp_path / "b.png").is_file()
    blue = np.all(bars == (178, 114, 0), axis=-1)  # series "one"
    orange = np.all(bars == (0, 159, 230), axis=-1)  # series "two"
    cols_blue = np.flatnonzero(blue.any(axis=0))
    assert blue.sum() > 500 and orange.sum() > 100
    # The 0.9 bar is taller than the 0.2 bar.
    heights = [blue[:, c].sum() for c in cols_blue]
    assert max(heights) > 3 * min(h for h in heights if h > 20)
    assert np.any(np.all(line == (178, 114, 0), axis=-1))
