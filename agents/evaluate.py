"""``graspenv eval``: play an agent over seeded episodes and measure it.

An agent is named by a spec (``scripted:NAME``, ``random`` or a model path), which
:func:`graspenv_agents.loading.load_agent` resolves.

Per episode: success (the last step's ``info["is_success"]``), return, length, time
to the first successful step (simulated seconds), and the means over its steps of
slip (m/s), grip force (N) and grasp quality (the Ferrari–Canny ε in ``info``, 0
without force closure). The summary gives the success rate with a 95 % Wilson
interval and the means of the rest (time to success over successful episodes).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from graspenv.viz import write_animation

from .loading import AgentSpec, make_env

__all__ = [
    "FIRST_SEED",
    "Episode",
    "Evaluation",
    "evaluate",
    "run_episodes",
    "summary_table",
    "wilson_interval",
]

#: Episode seeds start here unless told otherwise (the scripted strategies were
#: tuned on seeds 0–99; training evaluates on ``seed + 10_000`` onwards).
FIRST_SEED = 1000


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval of a success rate (95 % by default)."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(centre - half, 0.0), min(centre + half, 1.0)


@dataclass(frozen=True)
class Episode:
    """What one seeded episode measured (a row of ``episodes.csv``).

    Attributes:
        seed: the episode's seed.
        success: the last step's ``info["is_success"]``.
        episode_return: the sum of the rewards.
        length: steps.
        time_to_success: simulated seconds to the first successful step; NaN when
            never successful.
        slip: mean object slip over the steps, m/s.
        grip_force: mean grip force over the steps, newtons.
        quality: mean grasp quality over the steps (the Ferrari–Canny ε, 0 without
            force closure).
    """

    seed: int
    success: bool
    episode_return: float
    length: int
    time_to_success: float
    slip: float
    grip_force: float
    quality: float


@dataclass(frozen=True)
class Evaluation:
    """An agent's episodes in one environment.

    Attributes:
        env_id: the environment id.
        agent: the agent's label.
        kind: ``scripted``, ``random``, or the algorithm of a learned policy (``PPO``,
            ``SAC``).
        episodes: one per seed, in the order played.
    """

    env_id: str
    agent: str
    kind: str
    episodes: tuple[Episode, ...]

    @property
    def success(self) -> tuple[bool, ...]:
        return tuple(e.success for e in self.episodes)

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.success)) if self.episodes else 0.0

    def summary(self) -> dict[str, Any]:
        n = len(self.episodes)
        wins = sum(self.success)
        low, high = wilson_interval(wins, n)
        times = [e.time_to_success for e in self.episodes if e.success]

        def mean(name: str) -> float:
            return float(np.mean([getattr(e, name) for e in self.episodes])) if n else math.nan

        return {
            "env_id": self.env_id,
            "agent": self.agent,
            "kind": self.kind,
            "episodes": n,
            "success_rate": wins / n if n else 0.0,
            "success_ci_low": low,
            "success_ci_high": high,
            "mean_return": mean("episode_return"),
            "mean_length": mean("length"),
            "time_to_success_s": float(np.mean(times)) if times else math.nan,
            "mean_slip_m_s": mean("slip"),
            "mean_grip_force_n": mean("grip_force"),
            "mean_quality": mean("quality"),
        }

    def write(self, folder: str | Path) -> list[Path]:
        """``episodes.csv`` (one row per episode) and ``summary.json``."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        rows = [asdict(e) for e in self.episodes]
        with (folder / "episodes.csv").open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(asdict(self.episodes[0])))
            writer.writeheader()
            writer.writerows(rows)
        (folder / "summary.json").write_text(json.dumps(self.summary(), indent=2) + "\n")
        return [folder / "episodes.csv", folder / "summary.json"]


def evaluate(
    env_id: str,
    agent: AgentSpec,
    seeds: Sequence[int],
    config: str | Path | None = None,
    progress: Callable[[int, int], None] | None = None,
    video: str | Path | None = None,
) -> Evaluation:
    """Play one episode per seed; see the module docstring for what is measured.
    ``video`` (``.mp4`` or ``.gif``) records the first episode's top-down view."""
    kwargs = dict(agent.env_kwargs)
    if config is not None:
        kwargs["config"] = str(config)
    if video is not None:
        kwargs["render_mode"] = "rgb_array"
    env = make_env(env_id, kwargs, agent.wrapper)
    try:
        policy = agent.build(env)
        model_space = getattr(getattr(policy, "model", None), "observation_space", None)
        if model_space is not None and model_space.shape != env.observation_space.shape:
            raise ValueError(
                f"{agent.label} was trained on observations of shape {model_space.shape}, "
                f"{env_id} gives {env.observation_space.shape}"
            )
        episodes = []
        for i, seed in enumerate(seeds):
            frames: list[NDArray[np.uint8]] | None = [] if video is not None and i == 0 else None
            episodes.append(_episode(env, policy, seed, frames))
            if frames and video is not None:
                bgr = [np.ascontiguousarray(f[..., ::-1]) for f in frames]
                write_animation(bgr, video, float(env.metadata.get("render_fps", 30)))
            if progress is not None:
                progress(i + 1, len(seeds))
    finally:
        env.close()
    return Evaluation(env_id, agent.label, agent.kind, tuple(episodes))


def _episode(
    env: gym.Env[Any, Any], policy: Any, seed: int, frames: list[NDArray[np.uint8]] | None
) -> Episode:
    dt = float(env.unwrapped.dt)  # type: ignore[attr-defined]
    obs, info = env.reset(seed=seed)
    if frames is not None:
        frames.append(np.asarray(env.render()))
    policy.reset()
    if hasattr(policy, "seed"):
        policy.seed(seed)
    total, steps, first = 0.0, 0, math.nan
    slip, grip, quality = [], [], []
    done = False
    while not done:
        action, _ = policy.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action)
        if frames is not None:
            frames.append(np.asarray(env.render()))
        total += float(reward)
        steps += 1
        slip.append(float(info["slip"]))
        grip.append(float(info["grip_force"]))
        quality.append(float(info["epsilon"]) if info["force_closure"] else 0.0)
        if info["is_success"] and math.isnan(first):
            first = steps * dt
        done = terminated or truncated
    return Episode(
        seed,
        bool(info["is_success"]),
        total,
        steps,
        first,
        float(np.mean(slip)),
        float(np.mean(grip)),
        float(np.mean(quality)),
    )


def run_episodes(
    env_id: str,
    make_agent: Callable[[gym.Env[Any, Any]], Any],
    seeds: Sequence[int],
    **env_kwargs: Any,
) -> Evaluation:
    """``evaluate`` for an agent class or factory, with ``gym.make`` arguments."""
    name = getattr(make_agent, "name", getattr(make_agent, "__name__", "agent"))
    return evaluate(env_id, AgentSpec(str(name), make_agent, env_kwargs=env_kwargs), seeds)


def summary_table(summaries: Sequence[dict[str, Any]]) -> str:
    """A Markdown table of evaluation summaries."""
    lines = [
        "| agent | environment | success (95 % CI) | return | time to success (s) "
        "| slip (mm/s) | grip force (N) | quality ε |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for s in summaries:
        tts = s["time_to_success_s"]
        lines.append(
            f"| {s['agent']} | `{s['env_id']}` | {s['success_rate']:.0%} "
            f"({s['success_ci_low']:.0%}–{s['success_ci_high']:.0%}) | {s['mean_return']:.1f} "
            f"| {'—' if math.isnan(tts) else f'{tts:.2f}'} | {1000 * s['mean_slip_m_s']:.1f} "
            f"| {s['mean_grip_force_n']:.2f} | {s['mean_quality']:.3f} |"
        )
    return "\n".join(lines)
