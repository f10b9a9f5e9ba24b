"""Names into things: an environment id into an environment, an agent spec into an agent.

Training, evaluation and comparison all start here, so that none of them has to
import another to build what it plays. An agent is named by a spec:

- ``scripted:NAME``: a strategy from :data:`graspenv_agents.scripted.STRATEGIES`;
- ``random``: uniform random actions (seeded);
- ``still``: a hand lying still on the table (no motion, every finger down);
- a path: a stable-baselines3 model (``.zip``), a ``graspenv train`` run folder
  (its final policy ``policy.pt``, else ``model.zip``, else ``best_model.zip``) or
  the run folder of a plain ``python -m rl_zoo3.train`` (its final model
  ``<ENV>.zip``). The run's ``run.json``, or in a plain zoo run the zoo's own
  ``<ENV>/args.yml`` and ``<ENV>/config.yml``, supplies the algorithm and the
  environment arguments and wrapper it was trained with, and its
  ``vecnormalize.pkl`` (the zoo keeps it in ``<ENV>/``) the observation
  normalisation.

Nothing here imports stable-baselines3 or torch until a learned model is loaded
(:func:`graspenv_agents.hyperparams.algorithm` does), so ``graspenv eval`` of a
scripted strategy never pays for them.
"""

from __future__ import annotations

import json
import pickle
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

import graspenv

from .agent import Agent
from .hyperparams import ALGOS, algorithm
from .scripted import STRATEGIES
from .wrappers import WRAPPERS

__all__ = [
    "AgentSpec",
    "LearnedAgent",
    "RandomAgent",
    "check_env_id",
    "load_agent",
    "make_env",
]


def check_env_id(env_id: str) -> None:
    """``ValueError`` naming the registered ids unless ``env_id`` is one of them."""
    if env_id not in graspenv.ENV_IDS:
        raise ValueError(
            f"unknown environment {env_id!r}; expected one of {list(graspenv.ENV_IDS)}"
        )


def make_env(env_id: str, env_kwargs: dict[str, Any], wrapper: str) -> gym.Env[Any, Any]:
    """One environment as training and evaluation see it: ``gym.make`` with
    ``env_kwargs``, then the observation wrapper named ``wrapper`` (``""``: none).
    Picklable by reference, for subprocess workers."""
    check_env_id(env_id)
    if wrapper and wrapper not in WRAPPERS:
        raise ValueError(f"unknown env_wrapper {wrapper!r}; expected one of {list(WRAPPERS)}")
    env = gym.make(env_id, **env_kwargs)
    return WRAPPERS[wrapper](env) if wrapper else env


class RandomAgent(Agent):
    """Uniform random actions from a seeded action space (no memory)."""

    name = "random"

    def __init__(self, env: gym.Env[Any, Any], seed: int = 0) -> None:
        self.action_space = env.action_space
        self.action_space.seed(seed)

    def seed(self, seed: int) -> None:
        self.action_space.seed(seed)

    def _action(self, observation: Any, deterministic: bool) -> NDArray[np.float32]:
        return np.asarray(self.action_space.sample(), np.float32)


class StillAgent(Agent):
    """A hand lying still on the table where the task put it: no motion, every
    finger down. The floor of a task that an object could pass by itself."""

    name = "still"

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        size = int(np.prod(env.action_space.shape or ()))
        self._still = np.zeros(size, np.float32)
        # The touch flags: grip (vx, vy, turn, open, touch); fingers (vx, vy, touch) each.
        mode = env.unwrapped.action_mode  # type: ignore[attr-defined]
        self._still[4 if mode == "grip" else slice(2, None, 3)] = 1.0

    def _action(self, observation: Any, deterministic: bool) -> NDArray[np.float32]:
        return self._still.copy()


class LearnedAgent(Agent):
    """A stable-baselines3 model with the observation normalisation it trained with.

    The PPO and SAC MLP policies keep no memory: SB3 ignores their ``state`` and
    ``episode_start``, so :meth:`Agent.predict` need not pass them on.
    """

    def __init__(self, model: Any, normalizer: Any | None, name: str) -> None:
        self.model, self.normalizer, self.name = model, normalizer, name

    def _action(self, observation: Any, deterministic: bool) -> NDArray[np.float32]:
        if self.normalizer is not None:
            observation = self.normalizer.normalize_obs(observation)
        action, _ = self.model.predict(observation, deterministic=deterministic)
        return np.asarray(action, np.float32)


@dataclass(frozen=True)
class AgentSpec:
    """What an agent spec resolves to: a label, how to build the agent for an
    environment, and the environment it needs (``home``: the id it was written or
    trained for, None for any) with its ``gym.make`` arguments and wrapper."""

    label: str
    build: Callable[[gym.Env[Any, Any]], Any]
    home: str | None = None
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    wrapper: str = ""
    kind: str = "scripted"


def load_agent(spec: str, seed: int = 0) -> AgentSpec:
    """Resolve ``scripted:NAME``, ``random`` or a model path (see the module doc).

    Raises:
        ValueError: an unknown strategy or an unreadable model.
        FileNotFoundError: no such model file or run folder.
    """
    if spec == "random":
        return AgentSpec("random", lambda env: RandomAgent(env, seed), kind="random")
    if spec == "still":
        return AgentSpec("still", StillAgent, kind="still")
    if spec.startswith("scripted:"):
        name = spec.removeprefix("scripted:")
        if name not in STRATEGIES:
            raise ValueError(
                f"unknown scripted strategy {name!r}; expected one of {list(STRATEGIES)}"
            )
        strategy = STRATEGIES[name]
        return AgentSpec(
            name, strategy.agent, strategy.env_id, dict(strategy.env_kwargs), kind="scripted"
        )
    return _load_learned(Path(spec))


def _zoo_settings(folder: Path) -> Path | None:
    """The folder of a zoo run's settings (``<ENV>/`` beside ``<ENV>.zip``), if any."""
    found = [z for z in sorted(folder.iterdir()) if (z / "args.yml").is_file()]
    return found[0] if found else None


def _zoo_yaml(path: Path) -> dict[str, Any]:
    """One of the zoo's ``args.yml`` or ``config.yml``: an ordered mapping the zoo
    writes with PyYAML's Python tag, read here without constructing arbitrary
    objects (only that tag is allowed)."""
    import yaml

    class Loader(yaml.SafeLoader):
        pass

    def ordered(loader: yaml.SafeLoader, node: yaml.Node) -> dict[str, Any]:
        pairs = loader.construct_sequence(node.value[0], deep=True)
        return {key: value for key, value in pairs}

    Loader.add_constructor("tag:yaml.org,2002:python/object/apply:collections.OrderedDict", ordered)
    data: dict[str, Any] = yaml.load(path.read_text(), Loader=Loader)
    return data


def _zoo_run(settings: Path) -> dict[str, Any]:
    """What ``run.json`` holds, from a plain zoo run's settings folder."""
    args = _zoo_yaml(settings / "args.yml")
    return {
        "algo": args["algo"],
        "env_id": args["env"],
        "hyperparams": _zoo_yaml(settings / "config.yml"),
    }


def _load_learned(path: Path) -> AgentSpec:
    folder = path if path.is_dir() else path.parent
    zoo_settings = _zoo_settings(folder) if folder.is_dir() else None
    if path.is_dir():
        # The final policy first (what agents/policies/ ships), then the final models
        # (a plain zoo run's is <ENV>.zip), then the best evaluated one.
        final = [f"{zoo_settings.name}.zip"] if zoo_settings is not None else []
        for candidate in ["policy.pt", "model.zip", *final, "best_model.zip"]:
            if (path / candidate).is_file():
                path = path / candidate
                break
        else:
            raise FileNotFoundError(
                f"no policy.pt, model.zip, best_model.zip or zoo model <ENV>.zip in {path}"
            )
    if not path.is_file():
        raise FileNotFoundError(
            f"no model file {path} (agents are scripted:NAME, random, or a model path)"
        )
    run: dict[str, Any] = {}
    if (folder / "run.json").is_file():
        run = json.loads((folder / "run.json").read_text())
    elif zoo_settings is not None:
        run = _zoo_run(zoo_settings)
    algos = [run["algo"]] if "algo" in run else list(ALGOS)
    settings = run.get("hyperparams", {})
    model = None
    for algo in algos:
        cls = algorithm(algo)
        try:
            if path.suffix == ".pt":  # a policy alone (see agents/policies/README.md)
                policy_cls = cls.policy_aliases[settings.get("policy", "MlpPolicy")]
                model = policy_cls.load(path, device="cpu")
            else:
                model = cls.load(path, device="cpu")
            break
        except Exception:  # SB3 raises many kinds of error on a wrong file
            continue
    if model is None:
        raise ValueError(f"{path} is not a stable-baselines3 {' or '.join(algos).upper()} model")
    import torch

    # One thread: a small MLP acting on one observation runs fastest there, and its
    # actions then cannot depend on how many cores a process (or a Ray worker) has.
    torch.set_num_threads(1)
    normalizer = None
    beside = [folder] if zoo_settings is None else [folder, zoo_settings]
    pkl = next((d / "vecnormalize.pkl" for d in beside if (d / "vecnormalize.pkl").is_file()), None)
    if pkl is not None:
        with pkl.open("rb") as f:
            normalizer = pickle.load(f)
        normalizer.training = False
    label = f"{run.get('algo', type(model).__name__.lower()).upper()} ({folder.name})"
    return AgentSpec(
        label,
        lambda env: LearnedAgent(model, normalizer, label),
        home=run.get("env_id"),
        env_kwargs=dict(settings.get("env_kwargs", {})),
        wrapper=settings.get("env_wrapper", ""),
        kind=run.get("algo", "learned").upper(),
    )
