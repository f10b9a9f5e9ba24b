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


def main(argv: list[str] | None = None) -> int:
    """``python -m agents.scripted.evaluate [--episodes N] [--first-seed S]``: every
    strategy on its environment, as a Markdown table."""
    import argparse

    from agents.scripted import STRATEGIES

    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--strategy", action="append", help="one name (repeatable)")
    args = parser.parse_args(argv)
    seeds = range(args.first_seed, args.first_seed + args.episodes)
    print("| strategy | environment | success | mean length (steps) |")
    print("|---|---|---|---|")
    for name in args.strategy or STRATEGIES:
        env_id, agent = STRATEGIES[name]
        result = run_episodes(env_id, agent, seeds)
        low, high = wilson_interval(sum(result.success), len(result.success))
        print(
            f"| {name} | `{env_id}` | {result.success_rate:.0%} "
            f"(95 % CI {low:.0%}–{high:.0%}) | {np.mean(result.lengths):.1f} |",
            flush=True,
        )
    return 0


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95 % by default)."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return float(centre - half), float(centre + half)


if __name__ == "__main__":
    raise SystemExit(main())
