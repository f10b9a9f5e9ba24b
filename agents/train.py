"""``graspenv train``: a learned baseline, trained by rl-baselines3-zoo.

``graspenv train --env ENV --algo ALGO --seed S`` runs the zoo's own training,
in this process, with the same arguments a user would give it::

    python -m rl_zoo3.train --algo ALGO --env ENV --gym-packages graspenv \
        --conf-file agents/hyperparams/ALGO.yml --seed S --num-threads 1 ...

(it prints the full command first). The zoo builds the environments, the model,
the callbacks (stable-baselines3's evaluation, checkpoints and progress bar, and
any the file names, such as :class:`graspenv_agents.zoo.ScriptedDemonstrations`),
the TensorBoard log, and saves the model; this front adds only what a shipped
baseline needs beside it. The run folder is the zoo's,
``OUT/<algo>/graspenv-<Task>-v0_<N>/``:

- from the zoo: ``graspenv-<Task>-v0.zip`` (the final model), ``best_model.zip``,
  ``evaluations.npz``, ``rl_model_*.zip`` checkpoints, ``0.monitor.csv``, and
  ``graspenv-<Task>-v0/`` (``config.yml``, ``args.yml``, ``vecnormalize.pkl``);
- from here: ``run.json`` (environment, algorithm, seed, the entry's
  hyperparameters, the zoo command, package versions, the git commit, wall time),
  ``policy.pt`` (the final policy alone, what ``agents/policies/`` ships),
  ``vecnormalize.pkl`` beside it when observations are normalised, and
  ``evaluations.csv`` with ``learning_curve.png`` (success against steps).

TensorBoard logs go to ``OUT/tb/graspenv-<Task>-v0/<ALGO>_<N>/`` (``tensorboard
--logdir OUT/tb``); ``run.json`` names the run's.
"""

from __future__ import annotations

import importlib.util
import json
import platform
import shlex
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from graspenv.plots import line_chart

from .hyperparams import algorithm, default_file, load_hyperparams
from .loading import check_env_id

__all__ = ["TrainResult", "run_zoo", "train"]

#: What training needs beyond stable-baselines3 (the training extra): the zoo, and
#: what SB3 imports only once asked for TensorBoard logs and the progress bar.
TRAINING_PACKAGES = ("rl_zoo3", "tensorboard", "tqdm", "rich")

PACKAGES = (
    "graspenv",
    "gymnasium",
    "pybullet",
    "numpy",
    "opencv-python-headless",
    "stable-baselines3",
    "rl_zoo3",
    "torch",
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


def run_zoo(argv: Sequence[str]) -> None:
    """``python -m rl_zoo3.train ARGV`` in this process (the zoo reads ``sys.argv``)."""
    from rl_zoo3.train import train as zoo_train

    saved = sys.argv
    sys.argv = ["rl_zoo3.train", *argv]
    try:
        zoo_train()
    finally:
        sys.argv = saved


def _near(path: Path) -> Path:
    """``path`` relative to the working directory when it lies under it, so that the
    run record of a run made in a clone names its files as every clone has them."""
    try:
        return path.resolve().relative_to(Path.cwd().resolve())
    except ValueError:
        return path


def train(
    env_id: str,
    algo: str,
    seed: int = 0,
    config: str | Path | None = None,
    out: str | Path = "runs/train",
    steps: int | None = None,
    progress: Callable[[str], None] | None = None,
    progress_bar: bool = True,
    eval_freq: int = 5_000,
    eval_episodes: int = 10,
    save_freq: int = 25_000,
) -> TrainResult:
    """Train one baseline with the zoo; see the module docstring for the run folder.

    Args:
        env_id: a graspenv environment id.
        algo: ``ppo`` or ``sac``.
        seed: seeds the zoo's run (model, environments, evaluation).
        config: hyperparameter file (default ``agents/hyperparams/<algo>.yml``).
        out: the zoo's log folder.
        steps: override the entry's ``n_timesteps``.
        progress: receives the status lines (default: stderr).
        progress_bar: show stable-baselines3's progress bar while training.
        eval_freq, eval_episodes: the zoo's periodic evaluation (-1: none).
        save_freq: steps between checkpoints (-1: none).
    """
    check_env_id(env_id)
    for name in TRAINING_PACKAGES:
        # Without them the zoo or stable-baselines3 stops once training is under
        # way; the `graspenv` command turns this error into "install the training extra".
        if importlib.util.find_spec(name) is None:
            raise ModuleNotFoundError(f"no module named {name!r}", name=name)
    path = _near(Path(config) if config is not None else default_file(algo))
    settings = load_hyperparams(env_id, algo, path)  # fail before the zoo starts
    if steps is not None and steps < 1:
        raise ValueError(f"steps must be positive, got {steps}")
    out = _near(Path(out))
    # The zoo's own arguments: the file's entry, one torch thread (the cores go to
    # the environments), subprocess environments when there are several.
    argv = [
        "--algo", algo,
        "--env", env_id,
        "--gym-packages", "graspenv",
        "--conf-file", str(path),
        "--seed", str(seed),
        "--log-folder", str(out),
        "--tensorboard-log", str(out / "tb"),
        "--num-threads", "1",
        "--eval-freq", str(eval_freq),
        "--eval-episodes", str(eval_episodes),
        "--save-freq", str(save_freq),
        "--verbose", "0",
    ]  # fmt: skip
    if int(settings.get("n_envs", 1)) > 1:
        argv += ["--vec-env", "subproc"]
    if steps is not None:
        argv += ["--n-timesteps", str(steps)]
    if progress_bar:
        argv.append("--progress")
    say = progress or _stderr
    say("python -m rl_zoo3.train " + shlex.join(argv))
    runs, logs = out / algo, out / "tb" / env_id.replace("/", "-")
    before = set(runs.glob("*")) | set(logs.glob("*"))
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    start = time.perf_counter()
    run_zoo(argv)
    wall = time.perf_counter() - start
    # Run folders are named after the environment; its TensorBoard folder is its own.
    folder = _newest(runs, before, env_id.replace("/", "-") + "_")
    tensorboard = _newest(logs, before)
    if folder is None:
        raise RuntimeError(f"the zoo wrote no run folder under {runs}")
    name = env_id.replace("/", "-")
    model = algorithm(algo).load(folder / f"{name}.zip", device="cpu")
    model.policy.save(folder / "policy.pt")
    if (folder / name / "vecnormalize.pkl").is_file():
        shutil.copy(folder / name / "vecnormalize.pkl", folder / "vecnormalize.pkl")
    curve = write_learning_curve(folder, env_id, algo)
    final = float(curve[-1][2]) if curve else None
    record: dict[str, Any] = {
        "env_id": env_id,
        "algo": algo,
        "seed": seed,
        "hyperparams": settings,
        "hyperparams_file": str(path),
        "command": "python -m rl_zoo3.train " + shlex.join(argv),
        "versions": versions(),
        "git_commit": git_commit(Path(__file__).parent),
        "started": started,
        "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "wall_time_s": round(wall, 1),
        "tensorboard": None if tensorboard is None else str(tensorboard),
        "steps": int(model.num_timesteps),
        "last_eval_success": final,
    }
    _write_json(folder / "run.json", record)
    return TrainResult(folder, int(model.num_timesteps), wall, final)


def _newest(where: Path, before: set[Path], prefix: str = "") -> Path | None:
    """The newest folder named ``prefix…`` that the zoo made in ``where`` during this
    run (runs for other environments may share the log folder)."""
    made = [p for p in set(where.glob("*")) - before if p.name.startswith(prefix)]
    return max(made, key=lambda p: p.stat().st_mtime) if made else None


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
