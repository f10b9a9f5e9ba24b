"""``graspenv tune``: a hyperparameter sweep of a baseline with Ray Tune.

A search space file (TOML) names, for each hyperparameter to sweep, its
distribution, and in ``[fixed]`` the settings every trial shares (a shorter run, a
cheaper evaluation)::

    [fixed]
    n_timesteps = 20_000
    [space.learning_rate]
    loguniform = [1e-4, 3e-3]
    [space.gamma]
    choice = [0.9, 0.95, 0.98]

Distributions: ``uniform``, ``loguniform`` (``[low, high]``), ``randint`` (``[low,
high)``) and ``choice`` (a list). Each trial writes its hyperparameter file, the
algorithm's file with the trial's values in the environment's table (the format
``graspenv train --config`` reads, checked by the same loader), and trains from it
with :func:`graspenv_agents.train.train` on one CPU. After every periodic evaluation
it reports the success rate on the evaluation seeds (``seed + 10_000`` onwards,
held out from training and from the benchmark's seeds) to Tune, whose ASHA
scheduler stops the trials that trail. The best trial's file is written as
``best.toml`` (with its success rate in a comment) and ``sweep.csv`` lists every
trial.
"""

from __future__ import annotations

import csv
import json
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from graspenv import cluster

from .hyperparams import ALGOS, default_file, load_hyperparams, read_toml
from .loading import check_env_id

__all__ = ["TuneResult", "load_space", "to_toml", "tune"]

_DISTRIBUTIONS = ("uniform", "loguniform", "randint", "choice")


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
    data = read_toml(path, "search space")
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


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string is a JSON string
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML for {value!r}")


def to_toml(tables: dict[str, dict[str, Any]], comment: str = "") -> str:
    """A hyperparameter file: ``[defaults]`` and per-environment tables of plain
    values (what :func:`graspenv_agents.hyperparams.load_hyperparams` reads)."""
    lines = [f"# {line}" for line in comment.splitlines()]
    for name, table in tables.items():
        header = name if name.isidentifier() else json.dumps(name)
        lines += ["", f"[{header}]"]
        lines += [f"{key} = {_value(value)}" for key, value in table.items()]
    return "\n".join(lines).lstrip("\n") + "\n"


def trial_file(env_id: str, algo: str, base: Path, overrides: dict[str, Any], folder: Path) -> Path:
    """The algorithm's file with ``overrides`` in the environment's table, checked by
    the loader that training uses."""
    tables = tomllib.loads(base.read_text())
    tables[env_id] = {**tables.get(env_id, {}), **overrides}
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{algo}.toml"
    path.write_text(to_toml(tables, f"graspenv tune trial for {env_id}"))
    load_hyperparams(env_id, algo, path)
    return path


def _trial(config: dict[str, Any]) -> None:
    """One Tune trial (runs in a Ray worker): train from its file, reporting."""
    import numpy as np
    from ray import tune as ray_tune
    from stable_baselines3.common.callbacks import BaseCallback

    from .train import train

    class Report(BaseCallback):
        def _on_step(self) -> bool:
            successes = getattr(self.parent, "evaluations_successes", [])
            success = float(np.mean(successes[-1])) if successes else 0.0
            ray_tune.report({"success": success, "timesteps": int(self.num_timesteps)})
            return True

    meta = config["_graspenv"]
    overrides = {**meta["fixed"], **{k: v for k, v in config.items() if k != "_graspenv"}}
    folder = Path(meta["out"]) / "trials" / f"trial-{ray_tune.get_context().get_trial_id()}"
    path = trial_file(meta["env_id"], meta["algo"], Path(meta["base"]), overrides, folder)
    train(
        meta["env_id"],
        meta["algo"],
        seed=meta["seed"],
        config=path,
        out=folder,
        progress=lambda line: None,
        progress_bar=False,
        after_eval=Report(),
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
        out: folder for the trials, ``sweep.csv`` and ``best.toml``.
        seed: every trial's training seed.
        config: the hyperparameter file the trials start from (default
            ``agents/hyperparams/<algo>.toml``).
        address: an existing Ray cluster (default: a local instance).
    """
    check_env_id(env_id)
    if algo not in ALGOS:
        raise ValueError(f"unknown algorithm {algo!r}; expected one of {list(ALGOS)}")
    if trials < 1:
        raise ValueError(f"trials must be at least 1, got {trials}")
    fixed, space = load_space(space_file)
    base = Path(config) if config is not None else default_file(algo)
    out = Path(out).resolve()
    # Fail before any trial starts: the file with fixed settings must load.
    settings = load_hyperparams(env_id, algo, trial_file(env_id, algo, base, fixed, out / "check"))
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
    }
    steps = int(settings["n_timesteps"])
    scheduler = ASHAScheduler(
        time_attr="timesteps",
        max_t=steps,
        grace_period=max(1, min(steps, int(settings["eval_freq"]))),
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
    tables = tomllib.loads(base.read_text())
    tables[env_id] = {**tables.get(env_id, {}), **fixed, **best_params}
    best_file = out / "best.toml"
    best_file.write_text(
        to_toml(
            tables,
            f"graspenv tune: best of {len(rows)} trials of {algo} on {env_id}\n"
            f"success on the evaluation seeds: {best_success:.2f}\n"
            f"train with: graspenv train --env {env_id} --algo {algo} --config {best_file}",
        )
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
