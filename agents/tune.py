"""``graspenv tune``: a hyperparameter sweep of a baseline with Ray Tune.

A search space file (TOML) names, for each hyperparameter to sweep, its
distribution, and in ``[fixed]`` the settings every trial shares (a shorter run;
``eval_freq`` and ``eval_episodes`` set the trials' evaluation)::

    [fixed]
    n_timesteps = 20_000
    [space.learning_rate]
    loguniform = [1e-4, 3e-3]
    [space.gamma]
    choice = [0.9, 0.95, 0.98]

Distributions: ``uniform``, ``loguniform`` (``[low, high]``), ``randint`` (``[low,
high)``) and ``choice`` (a list). Each trial writes its hyperparameter file, the
environment's entry of the algorithm's zoo file with the trial's values (the format
``graspenv train --config`` and the zoo read, checked by the same loader), and
trains from it with rl-baselines3-zoo (:func:`graspenv_agents.train.train`) on one
CPU. Its file adds the callback :class:`TuneReport`, which evaluates the policy
every ``eval_freq`` steps on the evaluation seeds (``seed + 10_000`` onwards, held
out from training and from the benchmark's seeds) and reports the success rate to
Tune, whose ASHA scheduler stops the trials that trail. The best trial's entry is
written as ``best.yml`` (with its success rate in a comment, without the
reporting callback) and ``sweep.csv`` lists every trial.
"""

from __future__ import annotations

import csv
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import EvalCallback
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from graspenv import cluster

from .hyperparams import ALGOS, default_file, load_hyperparams, write_hyperparams
from .loading import check_env_id, make_env

__all__ = ["TuneReport", "TuneResult", "load_space", "tune"]

_DISTRIBUTIONS = ("uniform", "loguniform", "randint", "choice")
#: What a space file's [fixed] may set for the trials' evaluation (not hyperparameters).
EVALUATION = {"eval_freq": 5_000, "eval_episodes": 10}


@dataclass(frozen=True)
class TuneResult:
    best_file: Path
    best_success: float
    best_config: dict[str, Any]
    trials: int
    files: tuple[Path, ...]


def load_space(path: str | Path) -> tuple[dict[str, Any], dict[str, tuple[str, Any]]]:
    """The fixed settings and the swept ones (``name -> (distribution, bounds)``).

    Raises:
        FileNotFoundError: no such file.
        ValueError: malformed TOML or an unknown distribution, naming the file.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no search space file {path}")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{path}: {err}") from err
    unknown = set(data) - {"fixed", "space"}
    if unknown:
        raise ValueError(f"{path}: unknown tables {sorted(unknown)} (expected fixed, space)")
    space: dict[str, tuple[str, Any]] = {}
    for name, spec in data.get("space", {}).items():
        if not isinstance(spec, dict) or len(spec) != 1 or next(iter(spec)) not in _DISTRIBUTIONS:
            raise ValueError(
                f"{path}: space.{name} must hold one of {list(_DISTRIBUTIONS)}, got {spec!r}"
            )
        kind, bounds = next(iter(spec.items()))
        if kind != "choice" and (not isinstance(bounds, list) or len(bounds) != 2):
            raise ValueError(f"{path}: space.{name}.{kind} takes [low, high], got {bounds!r}")
        if kind == "choice" and (not isinstance(bounds, list) or not bounds):
            raise ValueError(f"{path}: space.{name}.choice takes a non-empty list")
        space[name] = (kind, bounds)
    if not space:
        raise ValueError(f"{path}: no [space.NAME] tables: nothing to sweep")
    return dict(data.get("fixed", {})), space


class TuneReport(EvalCallback):
    """stable-baselines3's periodic evaluation, on its own environment, reporting
    each success rate to Ray Tune (``success``, against ``timesteps``).

    The zoo builds callbacks from keyword arguments alone, so this one makes its
    evaluation environment from the environment id, arguments and wrapper.
    """

    def __init__(
        self,
        env_id: str,
        eval_freq: int,
        episodes: int,
        seed: int,
        env_kwargs: dict[str, Any] | None = None,
        env_wrapper: str = "",
    ) -> None:
        wrapper = env_wrapper
        env = DummyVecEnv([lambda: make_env(env_id, dict(env_kwargs or {}), wrapper)])
        env.seed(seed)
        super().__init__(env, n_eval_episodes=episodes, eval_freq=eval_freq, verbose=0)

    def _init_callback(self) -> None:
        # Observations normalised in training are normalised alike here (SB3 syncs
        # the statistics before each evaluation).
        if isinstance(self.training_env, VecNormalize) and not isinstance(
            self.eval_env, VecNormalize
        ):
            self.eval_env = VecNormalize(self.eval_env, training=False, norm_reward=False)
        super()._init_callback()

    def _on_step(self) -> bool:
        # As EvalCallback decides (its success list fills only with a log_path).
        evaluates = self.eval_freq > 0 and self.n_calls % self.eval_freq == 0
        keep_going = super()._on_step()
        if evaluates:
            from ray import tune as ray_tune

            success = float(np.mean(self._is_success_buffer)) if self._is_success_buffer else 0.0
            ray_tune.report({"success": success, "timesteps": int(self.num_timesteps)})
        return keep_going


def trial_file(
    env_id: str,
    algo: str,
    entry: dict[str, Any],
    folder: Path,
    seed: int,
    evaluation: dict[str, int],
) -> Path:
    """A file with the trial's entry and the reporting callback, checked by the
    loader that training uses."""
    report = {
        "graspenv_agents.tune.TuneReport": {
            "env_id": env_id,
            "eval_freq": evaluation["eval_freq"],
            "episodes": evaluation["eval_episodes"],
            "seed": seed + 10_000,
            "env_kwargs": dict(entry.get("env_kwargs", {})),
            "env_wrapper": str(entry.get("env_wrapper", "")),
        }
    }
    callbacks = entry.get("callback", [])
    callbacks = list(callbacks) if isinstance(callbacks, list) else [callbacks]
    path = write_hyperparams(
        folder / f"{algo}.yml",
        {env_id: {**entry, "callback": [*callbacks, report]}},
        f"graspenv tune trial for {env_id}",
    )
    load_hyperparams(env_id, algo, path)
    return path


def _trial(config: dict[str, Any]) -> None:
    """One Tune trial (runs in a Ray worker): train from its file with the zoo."""
    from ray import tune as ray_tune

    from .train import train

    meta = config["_graspenv"]
    overrides = {**meta["fixed"], **{k: v for k, v in config.items() if k != "_graspenv"}}
    folder = Path(meta["out"]) / "trials" / f"trial-{ray_tune.get_context().get_trial_id()}"
    entry = {**load_hyperparams(meta["env_id"], meta["algo"], Path(meta["base"])), **overrides}
    path = trial_file(meta["env_id"], meta["algo"], entry, folder, meta["seed"], meta["evaluation"])
    train(
        meta["env_id"],
        meta["algo"],
        seed=meta["seed"],
        config=path,
        out=folder,
        progress=lambda line: None,
        progress_bar=False,
        eval_freq=-1,
        save_freq=-1,
    )


def tune(
    env_id: str,
    algo: str,
    space_file: str | Path,
    trials: int = 8,
    out: str | Path = "runs/tune",
    seed: int = 0,
    config: str | Path | None = None,
    address: str | None = None,
    say: Callable[[str], None] | None = None,
) -> TuneResult:
    """Sweep ``algo``'s hyperparameters on ``env_id`` (see the module docstring).

    Args:
        env_id: a graspenv environment id.
        algo: ``ppo`` or ``sac``.
        space_file: the search space.
        trials: configurations drawn from the space.
        out: folder for the trials, ``sweep.csv`` and ``best.yml``.
        seed: every trial's training seed.
        config: the hyperparameter file the trials start from (default
            ``agents/hyperparams/<algo>.yml``).
        address: an existing Ray cluster (default: a local instance).
    """
    check_env_id(env_id)
    if algo not in ALGOS:
        raise ValueError(f"unknown algorithm {algo!r}; expected one of {list(ALGOS)}")
    if trials < 1:
        raise ValueError(f"trials must be at least 1, got {trials}")
    fixed, space = load_space(space_file)
    evaluation = {key: int(fixed.pop(key, default)) for key, default in EVALUATION.items()}
    base = Path(config) if config is not None else default_file(algo)
    out = Path(out).resolve()
    # Fail before any trial starts: the file with fixed settings must load.
    settings = {**load_hyperparams(env_id, algo, base), **fixed}
    trial_file(env_id, algo, settings, out / "check", seed, evaluation)
    cluster.connect(address)
    from ray import tune as ray_tune
    from ray.tune.schedulers import ASHAScheduler

    draw = {
        "uniform": lambda b: ray_tune.uniform(*b),
        "loguniform": lambda b: ray_tune.loguniform(*b),
        "randint": lambda b: ray_tune.randint(*b),
        "choice": ray_tune.choice,
    }
    param_space: dict[str, Any] = {name: draw[kind](b) for name, (kind, b) in space.items()}
    param_space["_graspenv"] = {
        "env_id": env_id,
        "algo": algo,
        "base": str(base.resolve()),
        "fixed": fixed,
        "out": str(out),
        "seed": seed,
        "evaluation": evaluation,
    }
    steps = int(settings["n_timesteps"])
    scheduler = ASHAScheduler(
        time_attr="timesteps",
        max_t=steps,
        grace_period=max(1, min(steps, evaluation["eval_freq"])),
        reduction_factor=2,
    )
    tuner = ray_tune.Tuner(
        ray_tune.with_resources(_trial, {"cpu": 1}),
        param_space=param_space,
        tune_config=ray_tune.TuneConfig(
            metric="success", mode="max", scheduler=scheduler, num_samples=trials
        ),
        run_config=ray_tune.RunConfig(name="sweep", storage_path=str(out / "ray"), verbose=1),
    )
    grid = tuner.fit()
    rows = []
    for i in range(len(grid)):
        result = grid[i]
        if result.error is not None:
            raise RuntimeError(f"a trial failed: {result.error}")
        params = {k: v for k, v in (result.config or {}).items() if k != "_graspenv"}
        metrics = result.metrics or {}
        rows.append({**params, **{k: metrics.get(k) for k in ("success", "timesteps")}})
    best = grid.get_best_result(metric="success", mode="max", scope="all")
    best_params = {k: v for k, v in (best.config or {}).items() if k != "_graspenv"}
    history = best.metrics_dataframe
    best_success = float(
        history["success"].max() if history is not None else (best.metrics or {})["success"]
    )
    best_file = out / "best.yml"
    write_hyperparams(
        best_file,
        {env_id: {**settings, **best_params}},
        f"graspenv tune: best of {len(rows)} trials of {algo} on {env_id}\n"
        f"success on the evaluation seeds: {best_success:.2f}\n"
        f"train with: graspenv train --env {env_id} --algo {algo} --config {best_file}",
    )
    load_hyperparams(env_id, algo, best_file)
    sweep = out / "sweep.csv"
    with sweep.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    if say is not None:
        say(f"best: {best_params} (success {best_success:.2f})")
    return TuneResult(best_file, best_success, best_params, len(rows), (best_file, sweep))
