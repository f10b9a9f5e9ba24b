"""The strategies a clone is fitted to answer from the state alone.

DAgger asks a strategy what it would do in states a learner reached, and a clone
can only fit labels that the observation determines. A strategy that kept its phase
from frame to frame labelled the same state differently from one episode to the
next. These play an episode, then ask a fresh strategy about its states in reverse
order: the actions must be the same.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import graspenv  # noqa: F401  (registers the environments)
from graspenv_agents.scripted.hold_catch import CupAndCatch
from graspenv_agents.scripted.push import PushFromBehind, RubFromTop


@pytest.mark.parametrize(
    ("env_id", "agent_cls", "seed", "phases"),
    [
        ("graspenv/SidePush-v0", PushFromBehind, 3, {"approach", "push"}),
        ("graspenv/TopRub-v0", RubFromTop, 5, set()),
        ("graspenv/CatchBall-v0", CupAndCatch, 2, {"cup", "surround", "pinch"}),
    ],
)
def test_strategy_answers_from_the_state_alone(
    env_id: str, agent_cls: type, seed: int, phases: set[str]
) -> None:
    env: gym.Env[Any, Any] = gym.make(env_id)
    try:
        obs, _ = env.reset(seed=seed)
        agent = agent_cls(env)
        states, actions, seen = [], [], set()
        for _ in range(120):
            action, _ = agent.predict(obs)
            states.append(np.array(obs))
            actions.append(action)
            seen.add(getattr(agent, "phase", None))
            obs, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                break
        assert phases <= seen  # the episode went through every phase
        if agent_cls is not CupAndCatch:  # fingers mode: it both placed and pressed
            touch = np.array(actions)[:, -1]
            assert (touch > 0).any() and (touch < 0).any()
        fresh = agent_cls(env)
        again = [fresh.predict(s)[0] for s in reversed(states)]
        np.testing.assert_allclose(np.array(again[::-1]), np.array(actions), atol=1e-6)
    finally:
        env.close()
