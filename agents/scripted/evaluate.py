"""Run a strategy over seeded episodes and count successes."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

import graspenv  # noqa: F401  (registers the environments)

__all__ = ["Episodes", "run_episodes"]


@dataclass(frozen=True)
class Episodes:
    """Outcomes of seeded episodes: success flags, returns and lengths."""

    success: tuple[bool, ...]
    returns: tuple[float, ...]
    lengths: tuple[int, ...]

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.success)) if self.success else 0.0


def run_episodes(
    env_id: str, make_agent: Callable[[gym.Env[Any, Any]], Any], seeds: range, **env_kwargs: Any
) -> Episodes:
    """Play one episode per seed with a fresh agent memory; success is the last
    step's ``info["is_success"]``."""
    env = gym.make(env_id, **env_kwargs)
    agent = make_agent(env)
    success, returns, lengths = [], [], []
    try:
        for seed in seeds:
            obs, info = env.reset(seed=seed)
            agent.reset()
            total, steps, done = 0.0, 0, False
            while not done:
                action, _ = agent.predict(obs)
                obs, reward, terminated, truncated, info = env.step(action)
                total += float(reward)
                steps += 1
                done = terminated or truncated
            success.append(bool(info["is_success"]))
            returns.append(total)
            lengths.append(steps)
    finally:
        env.close()
    return Episodes(tuple(success), tuple(returns), tuple(lengths))
