"""``graspenv train``: stable-baselines3 PPO or SAC on a graspenv environment.

A run folder records everything needed to reproduce and to use the result:

- ``run.json``: environment, algorithm, seed, the resolved hyperparameters, the
  command, package versions, the git commit, wall time and steps;
- ``model.zip`` (final) and ``best_model.zip`` (best periodic evaluation), with
  ``vecnormalize.pkl`` when observations are normalised;
- ``checkpoints/``, ``progress.csv`` (every logged value), ``tb/`` (the same values
  as TensorBoard event files, from stable-baselines3's logger);
- ``evaluations.csv`` and ``learning_curve.png``: periodic deterministic
  evaluation (success rate and return against training steps).
"""

from __future__ import annotations

import functools
import importlib.util
import json
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
)
from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
from stable_baselines3.common.logger import Logger, make_output_format
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

from graspenv.plots import line_chart

from .hyperparams import algorithm, algorithm_kwargs, load_hyperparams
from .loading import check_env_id, load_agent, make_env

__all__ = ["TrainResult", "make_vec_env", "train"]

#: What stable-baselines3 needs for the TensorBoard logs and the progress bar (the
#: training extra), which it imports only once asked for them.
LOGGING_PACKAGES = ("tensorboard", "tqdm", "rich")

PACKAGES = (
    "graspenv",
    "gymnasium",
    "pybullet",
    "numpy",
    "opencv-python-headless",
    "stable-baselines3",
    "torch",
)


def make_vec_env(
    env_id: str,
    settings: dict[str, Any],
    n_envs: int,
    seed: int,
    monitor_dir: Path | None = None,
) -> Any:
    """``n_envs`` monitored environments (subprocesses when more than one)."""
    factory = functools.partial(
        make_env, env_id, dict(settings["env_kwargs"]), settings["env_wrapper"]
    )
    return sb3_make_vec_env(
        lambda: factory(),
        n_envs=n_envs,
        seed=seed,
        monitor_dir=None if monitor_dir is None else str(monitor_dir),
        monitor_kwargs={"info_keywords": ("is_success",)},
        vec_env_cls=SubprocVecEnv if n_envs > 1 else DummyVecEnv,
    )


@dataclass(frozen=True)
class TrainResult:
    folder: Path
    steps: int
    wall_time: float
    final_success: float | None

    def text(self) -> str:
        success = "n/a" if self.final_success is None else f"{self.final_success:.0%}"
        return (
            f"trained {self.steps} steps in {self.wall_time / 60:.1f} min; "
            f"last evaluation success {success}; run folder {self.folder}"
        )


def versions() -> dict[str, str]:
    found = {"python": platform.python_version(), "platform": platform.platform()}
    for name in PACKAGES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


def git_commit(where: Path) -> str | None:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True, check=True
        )
        dirty = subprocess.run(
            ["git", "status", "--porcelain"], cwd=where, capture_output=True, text=True, check=True
        )
    except (OSError, subprocess.CalledProcessError):
        return None
    return out.stdout.strip() + ("+uncommitted" if dirty.stdout.strip() else "")


def run_folder(root: Path, env_id: str, algo: str, seed: int) -> Path:
    """A new folder ``root/<Task>-<algo>-s<seed>`` (``-2``, ``-3``… if taken)."""
    base = f"{env_id.split('/')[-1].removesuffix('-v0')}-{algo}-s{seed}"
    folder = root / base
    k = 2
    while folder.exists():
        folder = root / f"{base}-{k}"
        k += 1
    folder.mkdir(parents=True)
    return folder


def train(
    env_id: str,
    algo: str,
    seed: int = 0,
    config: str | Path | None = None,
    out: str | Path = "runs/train",
    steps: int | None = None,
    n_envs: int | None = None,
    progress: Callable[[str], None] | None = None,
    progress_bar: bool = True,
    after_eval: BaseCallback | None = None,
) -> TrainResult:
    """Train and evaluate one agent; see the module docstring for the run folder.

    Args:
        env_id: a graspenv environment id.
        algo: ``ppo`` or ``sac``.
        seed: seeds the algorithm and the environments (evaluation: ``seed + 10_000``).
        config: hyperparameter file (default ``agents/hyperparams/<algo>.toml``).
        out: parent of the run folder.
        steps, n_envs: override the file's ``n_timesteps`` and ``n_envs``.
        progress: receives the status lines before training starts (default: stderr).
        progress_bar: show stable-baselines3's progress bar (tqdm and rich) while
            training; what training logs goes to ``progress.csv`` and ``tb/``.
        after_eval: a callback run after each periodic evaluation (its ``parent``
            is SB3's ``EvalCallback``; ``graspenv tune`` reports from it).
    """
    check_env_id(env_id)
    for name in LOGGING_PACKAGES:
        # Without them stable-baselines3 stops on an assertion once training is under
        # way; the `graspenv` command turns this error into "install the training extra".
        if importlib.util.find_spec(name) is None:
            raise ModuleNotFoundError(f"no module named {name!r}", name=name)
    settings = load_hyperparams(env_id, algo, config)
    if steps is not None:
        settings["n_timesteps"] = steps
    if n_envs is not None:
        settings["n_envs"] = n_envs
    if settings["n_envs"] == 0:
        settings["n_envs"] = len(os.sched_getaffinity(0))
    if settings["n_timesteps"] < 1 or settings["n_envs"] < 1:
        raise ValueError("n_timesteps and n_envs must be positive")
    make_env(env_id, settings["env_kwargs"], settings["env_wrapper"]).close()  # fail early

    torch.set_num_threads(settings["torch_threads"])
    folder = run_folder(Path(out), env_id, algo, seed)
    record: dict[str, Any] = {
        "env_id": env_id,
        "algo": algo,
        "seed": seed,
        "hyperparams": settings,
        "hyperparams_file": str(config or "built-in"),
        "command": sys.argv,
        "versions": versions(),
        "git_commit": git_commit(Path(__file__).parent),
        "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    _write_json(folder / "run.json", record)

    n = settings["n_envs"]
    envs = make_vec_env(env_id, settings, n, seed, folder / "monitor")
    eval_env = make_vec_env(env_id, settings, 1, seed + 10_000)
    if settings["normalize"]:
        gamma = float(settings.get("gamma", 0.99))
        envs = VecNormalize(envs, gamma=gamma)
        eval_env = VecNormalize(eval_env, training=False, norm_reward=False, gamma=gamma)
    model = algorithm(algo)(
        settings["policy"], envs, seed=seed, verbose=0, **algorithm_kwargs(settings)
    )
    if settings["demo_episodes"]:
        demos = prefill(model, env_id, settings, seed + 20_000)
        record["demonstrations"] = demos
        _write_json(folder / "run.json", record)
        (progress or _stderr)(
            f"replay buffer filled with {settings['demo_episodes']} episodes of "
            f"{settings['demonstrations']} ({demos['transitions']} transitions, "
            f"{demos['successes']} successes)"
        )
    model.set_logger(
        Logger(
            str(folder),
            [
                make_output_format("csv", str(folder)),
                make_output_format("tensorboard", str(folder / "tb")),
            ],
        )
    )
    evaluation = EvalCallback(
        eval_env,
        n_eval_episodes=settings["eval_episodes"],
        eval_freq=max(settings["eval_freq"] // n, 1),
        log_path=str(folder),
        best_model_save_path=str(folder),
        deterministic=True,
        verbose=0,
        callback_after_eval=after_eval,
    )
    callbacks = CallbackList(
        [
            evaluation,
            CheckpointCallback(
                max(settings["checkpoint_freq"] // n, 1),
                str(folder / "checkpoints"),
                name_prefix="model",
                save_vecnormalize=True,
            ),
        ]
    )
    start = time.perf_counter()
    try:
        model.learn(settings["n_timesteps"], callback=callbacks, progress_bar=progress_bar)
    finally:
        envs.close()
        eval_env.close()
        model.logger.close()
    wall = time.perf_counter() - start
    model.save(folder / "model.zip")
    if settings["normalize"]:
        model.get_vec_normalize_env().save(str(folder / "vecnormalize.pkl"))
    curve = write_learning_curve(folder, env_id, algo)
    final = float(curve[-1][2]) if curve else None
    record.update(
        finished=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        wall_time_s=round(wall, 1),
        steps=int(model.num_timesteps),
        last_eval_success=final,
    )
    _write_json(folder / "run.json", record)
    return TrainResult(folder, int(model.num_timesteps), wall, final)


def prefill(model: Any, env_id: str, settings: dict[str, Any], first_seed: int) -> dict[str, int]:
    """Play ``demo_episodes`` episodes of the scripted strategy and add every
    transition to the model's replay buffer (what the policy will see: the same
    environment arguments and wrapper)."""
    spec = load_agent(settings["demonstrations"])
    env = make_env(env_id, settings["env_kwargs"], settings["env_wrapper"])
    agent = spec.build(env)
    transitions = successes = 0
    try:
        for episode in range(settings["demo_episodes"]):
            obs, info = env.reset(seed=first_seed + episode)
            agent.reset()
            done = False
            while not done:
                action, _ = agent.predict(obs)
                next_obs, reward, terminated, truncated, info = env.step(action)
                model.replay_buffer.add(
                    np.asarray(obs)[None],
                    np.asarray(next_obs)[None],
                    np.asarray(action)[None],
                    np.array([reward]),
                    np.array([terminated]),
                    [{"TimeLimit.truncated": truncated and not terminated}],
                )
                obs, done = next_obs, terminated or truncated
                transitions += 1
            successes += bool(info["is_success"])
    finally:
        env.close()
    return {
        "episodes": settings["demo_episodes"],
        "transitions": transitions,
        "successes": successes,
    }


def _write_json(path: Path, data: dict[str, Any]) -> None:
    path.write_text(json.dumps(data, indent=2, default=str) + "\n")


def write_learning_curve(folder: Path, env_id: str, algo: str) -> list[tuple[int, float, float]]:
    """``evaluations.csv`` and ``learning_curve.png`` from the periodic evaluations
    (steps, mean return, success rate)."""
    path = folder / "evaluations.npz"
    if not path.is_file():
        return []
    data = np.load(path)
    steps = data["timesteps"]
    returns = data["results"].mean(axis=1)
    success = (
        data["successes"].mean(axis=1) if len(data["successes"]) else np.full(len(steps), np.nan)
    )
    rows = [(int(s), float(r), float(p)) for s, r, p in zip(steps, returns, success, strict=True)]
    lines = ["steps,mean_return,success_rate"] + [f"{s},{r:.4f},{p:.4f}" for s, r, p in rows]
    (folder / "evaluations.csv").write_text("\n".join(lines) + "\n")
    name = env_id.split("/")[-1]
    line_chart(
        {"success rate": (steps.tolist(), success.tolist())},
        folder / "learning_curve.png",
        f"{name}, {algo.upper()}: deterministic evaluation",
        "training steps",
        "success rate",
        ylim=(0.0, 1.0),
    )
    return rows


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)
