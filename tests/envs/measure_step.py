"""Where an environment step's time goes, beside panda-gym's whole step.

Times each stage of ``GraspEnv.step`` from inside (the pipeline's stages from
``Simulation.step``'s own report) over 1 000 steps of an environment with its
scripted agent (or random actions), then panda-gym's ``PandaPickAndPlace-v3`` with
random actions in the same process.

Run: ``python -m tests.envs.measure_step [STRATEGY] [--random]`` (default
``pinch-and-turn``; about 15 s).
"""

from __future__ import annotations

import collections
import sys
import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym

import graspenv  # noqa: F401  (registers the environments)
import graspenv.envs.grasp_env as grasp_env
import graspenv.simulation as simulation
import graspenv.surface.controller as controller
from graspenv.bench.speed import PEER_ID, peer_available, peer_steps_per_second
from graspenv_agents.scripted import STRATEGIES

SPENT: collections.Counter[str] = collections.Counter()


def _timed(owner: Any, name: str, label: str) -> None:
    original: Callable[..., Any] = getattr(owner, name)

    def timed(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            SPENT[label] += time.perf_counter() - start

    setattr(owner, name, timed)


def _instrument() -> None:
    step = simulation.Simulation.step

    def timed_step(self: simulation.Simulation, mask: Any) -> simulation.FrameReport:
        start = time.perf_counter()
        report = step(self, mask)
        SPENT["pipeline (Simulation.step)"] += time.perf_counter() - start
        for stage, seconds in report.timings.items():
            SPENT[f"  {stage}"] += seconds
        return report

    simulation.Simulation.step = timed_step  # type: ignore[method-assign]
    _timed(grasp_env, "render_mask", "rendering the masks")
    _timed(grasp_env.GraspEnv, "_read_state", "state and grasp metrics")
    _timed(controller.FingerController, "apply", "finger controller")
    _timed(controller.FingerController, "advance", "finger controller")
    _timed(grasp_env.GraspEnv, "step", "the whole step")


def main(argv: list[str]) -> None:
    name = next((a for a in argv if not a.startswith("--")), "pinch-and-turn")
    random = "--random" in argv
    strategy = STRATEGIES[name]
    env = gym.make(strategy.env_id, **strategy.env_kwargs)
    agent = strategy.agent(env)
    env.action_space.seed(0)
    _instrument()

    def play(steps: int) -> float:
        obs, _ = env.reset(seed=0)
        start = time.perf_counter()
        for _ in range(steps):
            action = env.action_space.sample() if random else agent.predict(obs)[0]
            obs, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                obs, _ = env.reset()
        return time.perf_counter() - start

    play(100)
    SPENT.clear()
    steps = 1000
    wall = play(steps)
    kind = "random actions" if random else name
    print(
        f"{strategy.env_id}, {kind}: {steps / wall:.0f} steps/s, {wall / steps * 1e3:.2f} ms a step"
    )
    for label, seconds in sorted(SPENT.items(), key=lambda item: -item[1]):
        print(f"  {label:32s} {seconds / steps * 1e3:.3f} ms a step")
    if peer_available():
        rate = peer_steps_per_second(600)
        print(f"{PEER_ID}, random actions: {rate:.0f} steps/s, {1e3 / rate:.2f} ms a step")


if __name__ == "__main__":
    main(sys.argv[1:])
