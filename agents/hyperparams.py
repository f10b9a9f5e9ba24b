"""Per-environment hyperparameter files: rl-baselines3-zoo's own YAML format.

One file per algorithm (``agents/hyperparams/ppo.yml``, ``sac.yml``), one entry per
environment id, read by the zoo (``python -m rl_zoo3.train --conf-file FILE``) and
so by ``graspenv train``, which runs the zoo. Keys are the zoo's: the algorithm's
constructor arguments (``policy_kwargs`` as the zoo's Python string, e.g.
``"dict(net_arch=[256, 256])"``) and its own run keys (:data:`ZOO_KEYS`:
``n_timesteps``, ``policy``, ``n_envs``, ``normalize``, ``env_wrapper``,
``callback`` and the rest, as the zoo documents them). The graspenv-specific pieces
are named by their import path: ``graspenv_agents.wrappers.RelativeGoal`` and
``graspenv_agents.zoo.ScriptedDemonstrations``.

:func:`load_hyperparams` reads one entry and checks it before the zoo does, so that
a typo stops with the file, the entry and the key named rather than deep in a
training run.
"""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

__all__ = [
    "ALGOS",
    "ZOO_KEYS",
    "algorithm",
    "default_file",
    "load_hyperparams",
    "write_hyperparams",
]

ALGOS = ("ppo", "sac")
#: The zoo's own keys beside the algorithm's arguments (rl_zoo3.exp_manager).
ZOO_KEYS = frozenset(
    {
        "n_timesteps",
        "policy",
        "n_envs",
        "normalize",
        "env_wrapper",
        "vec_env_wrapper",
        "env_kwargs",
        "callback",
        "frame_stack",
        "monitor_kwargs",
        "normalize_kwargs",
    }
)


def default_file(algo: str) -> Path:
    return Path(__file__).parent / "hyperparams" / f"{algo}.yml"


def algorithm(algo: str) -> Any:
    """The stable-baselines3 class for ``ppo`` or ``sac``."""
    if algo not in ALGOS:
        raise ValueError(f"unknown algorithm {algo!r}; expected one of {list(ALGOS)}")
    # Here, not at the top: `graspenv eval` of a scripted strategy, and every other
    # `graspenv` command, imports this module and should not load stable-baselines3.
    from stable_baselines3 import PPO, SAC

    return {"ppo": PPO, "sac": SAC}[algo]


def _read(path: Path) -> dict[str, Any]:
    import yaml  # the training extra (rl-zoo3 needs it); only when a file is read

    if not path.is_file():
        raise FileNotFoundError(f"no hyperparameter file {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        # One line: what went wrong, and where (PyYAML's own message spans several).
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or type(err).__name__
        raise ValueError(f"{path}: malformed YAML{where}: {problem}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping of environment ids to entries")
    return data


def load_hyperparams(env_id: str, algo: str, path: str | Path | None = None) -> dict[str, Any]:
    """The entry for ``env_id`` in ``algo``'s file (default
    ``agents/hyperparams/<algo>.yml``), as the zoo will read it.

    Raises:
        FileNotFoundError: no such file.
        ValueError: malformed YAML, no entry for ``env_id``, an unknown key, or a
            bad ``n_timesteps``, naming the file and the entry.
    """
    cls = algorithm(algo)
    path = Path(path) if path is not None else default_file(algo)
    data = _read(path)
    if env_id not in data:
        raise ValueError(f"{path}: no entry for {env_id} (entries: {sorted(data)})")
    entry = data[env_id]
    if not isinstance(entry, dict):
        raise ValueError(f"{path}: {env_id} must be a mapping of hyperparameters")
    accepted = set(inspect.signature(cls.__init__).parameters) - {"self", "env", "policy"}
    for key in entry:
        if key not in ZOO_KEYS and key not in accepted:
            raise ValueError(f"{path}: {env_id}: unknown key {key!r} for {algo}")
    steps = entry.get("n_timesteps")
    if not isinstance(steps, int | float) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"{path}: {env_id}: n_timesteps must be a positive number, got {steps!r}")
    return dict(entry)


def write_hyperparams(path: Path, entries: dict[str, dict[str, Any]], comment: str = "") -> Path:
    """Write a file of ``entries`` (environment id -> hyperparameters) with a
    comment at its top, in the format :func:`load_hyperparams` and the zoo read."""
    import yaml

    header = "".join(f"# {line}\n" for line in comment.splitlines())
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(header + yaml.safe_dump(entries, sort_keys=False))
    return path
