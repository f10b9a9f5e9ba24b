"""The finger strategies (push from behind, rub from the top) solve their tasks.

Measured over seeds 0..99 with the default environments: PushFromBehind 100/100 on
SidePush-v0, RubFromTop 100/100 on TopRub-v0. The tests play 10 seeds each and ask
for 80 %, leaving margin for small changes in the physics.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import graspenv  # noqa: F401  (registers the environments)
from graspenv_agents.evaluate import run_episodes
from graspenv_agents.scripted.base import ScriptedAgent
from graspenv_agents.scripted.push import PushFromBehind, RubFromTop

# Seeds 100-109: the strategies were tuned on seeds 0-99.
SEEDS = range(100, 110)


@pytest.mark.parametrize(
    ("env_id", "agent_cls"),
    [("graspenv/SidePush-v0", PushFromBehind), ("graspenv/TopRub-v0", RubFromTop)],
)
def test_strategy_succeeds(env_id: str, agent_cls: type[ScriptedAgent]) -> None:
    """At least 80 % of ten seeded episodes end with ``info["is_success"]``."""
    episodes = run_episodes(env_id, agent_cls, SEEDS)
    assert episodes.success_rate >= 0.8, episodes.success


def test_rub_reads_mask_observations() -> None:
    """The strategy takes the ``state`` entry of ``"mask"`` observations and still
    succeeds (same physics, so the same outcome as with state observations)."""
    episodes = run_episodes("graspenv/TopRub-v0", RubFromTop, range(100, 103), obs_mode="mask")
    assert episodes.success_rate >= 2 / 3, episodes.success


def test_push_lifts_at_the_goal() -> None:
    """Once the box is within the stop distance of the goal, both fingers lift."""
    env: gym.Env[Any, Any] = gym.make("graspenv/SidePush-v0")
    try:
        obs, _ = env.reset(seed=0)
        agent = PushFromBehind(env)
        layout = env.unwrapped.observation_layout  # type: ignore[attr-defined]
        vector = np.array(obs, dtype=np.float32)
        goal = vector[layout["goal"]]  # a view: writing it edits the vector
        goal[:2] = vector[layout["object_position"]][:2]
        action, _ = agent.predict(vector)
        assert action.shape == env.action_space.shape
        assert np.all(action.reshape(-1, 3)[:, 2] < 0.0)
        assert np.allclose(action.reshape(-1, 3)[:, :2], 0.0)
    finally:
        env.close()


def test_batched_predict_keeps_shape() -> None:
    """A VecEnv-style batch of one gives a batch of one action in the space's bounds."""
    env: gym.Env[Any, Any] = gym.make("graspenv/TopRub-v0")
    try:
        obs, _ = env.reset(seed=1)
        agent = RubFromTop(env)
        action, _ = agent.predict(np.asarray(obs)[None, :], episode_start=np.array([True]))
        shape = env.action_space.shape
        assert shape is not None
        assert action.shape == (1, *shape)
        assert np.all(np.abs(action) <= 1.0)
    finally:
        env.close()


def test_push_to_goal_slides_the_box_without_gripping_it() -> None:
    """SqueezeSlide's second strategy: the same push, in ``fingers`` action mode. It
    meets the bar without ever holding the box in force closure (quality ε 0)."""
    episodes = run_episodes(
        "graspenv/SqueezeSlide-v0", PushFromBehind, SEEDS, action_mode="fingers"
    )
    assert episodes.success_rate >= 0.8, episodes.success
    assert episodes.summary()["mean_quality"] < 1e-3
