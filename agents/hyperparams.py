"""Per-environment hyperparameter files, in RL Zoo's style.

One TOML file per algorithm (``agents/hyperparams/ppo.toml``, ``sac.toml``). A
``[defaults]`` table applies to every environment; a table named by the environment
id (``["graspenv/TurnInPlace-v0"]``) overrides it key by key. Keys are the
algorithm's own constructor arguments plus these run settings:

- ``n_timesteps``: environment steps to train for;
- ``policy``: ``MlpPolicy`` (state observations) or ``MultiInputPolicy`` (dicts);
- ``n_envs``: environments stepped in parallel (``0``: one per available core);
- ``normalize``: wrap the environments in ``VecNormalize`` (observations and rewards);
- ``env_kwargs``: keyword arguments for ``gym.make``;
- ``env_wrapper``: a name from :data:`graspenv_agents.wrappers.WRAPPERS`;
- ``eval_freq``, ``eval_episodes``: periodic deterministic evaluation (steps, episodes);
- ``checkpoint_freq``: steps between saved checkpoints;
- ``torch_threads``: threads torch may use (1 keeps the cores for the environments);
- ``demonstrations``, ``demo_episodes``: off-policy algorithms only: before training,
  fill the replay buffer with this many episodes of a scripted strategy
  (``"scripted:NAME"``), seeded apart from training and evaluation.

``policy_kwargs.activation_fn`` is a name (``tanh``, ``relu``, ``elu``);
``replay_buffer_class`` may be ``"HerReplayBuffer"`` (hindsight relabelling, with
``env_kwargs.obs_mode = "goal"`` and ``policy = "MultiInputPolicy"``), its options in
``replay_buffer_kwargs``.
"""

from __future__ import annotations

import inspect
import tomllib
from pathlib import Path
from typing import Any

__all__ = ["ALGOS", "RUN_KEYS", "default_file", "load_hyperparams", "read_toml"]

ALGOS = ("ppo", "sac")
RUN_KEYS = {
    "n_timesteps": 100_000,
    "policy": "MlpPolicy",
    "n_envs": 1,
    "normalize": False,
    "env_kwargs": {},
    "env_wrapper": "",
    "eval_freq": 10_000,
    "eval_episodes": 10,
    "checkpoint_freq": 50_000,
    "torch_threads": 1,
    "demonstrations": "",
    "demo_episodes": 0,
}
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu")
REPLAY_BUFFERS = ("HerReplayBuffer",)


def default_file(algo: str) -> Path:
    return Path(__file__).parent / "hyperparams" / f"{algo}.toml"


def read_toml(path: Path, what: str) -> dict[str, Any]:
    """The tables of the TOML file at ``path`` (a hyperparameter or search space file).

    Raises:
        FileNotFoundError: no such file (``no {what} file {path}``).
        ValueError: malformed TOML, naming the file.
    """
    if not path.is_file():
        raise FileNotFoundError(f"no {what} file {path}")
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{path}: malformed TOML: {err}") from None


def algorithm(algo: str) -> Any:
    """The stable-baselines3 class for ``ppo`` or ``sac``."""
    if algo not in ALGOS:
        raise ValueError(f"unknown algorithm {algo!r}; expected one of {list(ALGOS)}")
    # Here, not at the top: `graspenv eval` of a scripted strategy, and every other
    # `graspenv` command, imports this module and should not load stable-baselines3.
    from stable_baselines3 import PPO, SAC

    return {"ppo": PPO, "sac": SAC}[algo]


def load_hyperparams(env_id: str, algo: str, path: str | Path | None = None) -> dict[str, Any]:
    """The settings for one environment and algorithm: run settings (every key of
    :data:`RUN_KEYS`) and algorithm arguments, as plain TOML values.

    Raises:
        FileNotFoundError: no such file.
        ValueError: malformed TOML, an unknown key, or a wrong type, naming the
            file and table.
    """
    cls = algorithm(algo)
    path = Path(path) if path is not None else default_file(algo)
    data = read_toml(path, "hyperparameter")
    for name, table in data.items():
        if not isinstance(table, dict):
            raise ValueError(f"{path}: top-level key {name!r} must be a table")
    settings: dict[str, Any] = dict(RUN_KEYS)
    accepted = set(inspect.signature(cls.__init__).parameters) - {"self", "env", "policy"}
    for section in ("defaults", env_id):
        table = data.get(section, {})
        for key, value in table.items():
            if key not in RUN_KEYS and key not in accepted:
                raise ValueError(f"{path}: [{section}] unknown key {key!r} for {algo}")
            default = RUN_KEYS.get(key)
            if default is not None and not _same_kind(default, value):
                raise ValueError(
                    f"{path}: [{section}] {key} must be {type(default).__name__}, got {value!r}"
                )
            settings[key] = value
    if settings["demo_episodes"] and not settings["demonstrations"].startswith("scripted:"):
        raise ValueError(f"{path}: demonstrations must name a scripted:STRATEGY")
    if settings["demo_episodes"] and algo == "ppo":
        raise ValueError(f"{path}: demonstrations need an off-policy algorithm (sac)")
    buffer = settings.get("replay_buffer_class")
    if buffer is not None and buffer not in REPLAY_BUFFERS:
        raise ValueError(
            f"{path}: replay_buffer_class must be one of {list(REPLAY_BUFFERS)}, got {buffer!r}"
        )
    activation = settings.get("policy_kwargs", {}).get("activation_fn")
    if activation is not None and activation not in ACTIVATIONS:
        raise ValueError(
            f"{path}: policy_kwargs.activation_fn must be one of {list(ACTIVATIONS)}, "
            f"got {activation!r}"
        )
    return settings


def _same_kind(default: Any, value: Any) -> bool:
    if isinstance(default, bool) or isinstance(value, bool):
        return isinstance(value, bool) and isinstance(default, bool)
    if isinstance(default, int):
        return isinstance(value, int)
    return isinstance(value, type(default))


def algorithm_kwargs(settings: dict[str, Any]) -> dict[str, Any]:
    """The settings the algorithm's constructor takes (activation names resolved)."""
    kwargs = {k: v for k, v in settings.items() if k not in RUN_KEYS}
    policy_kwargs = dict(kwargs.get("policy_kwargs", {}))
    if "activation_fn" in policy_kwargs:
        import torch  # here for the same reason as in `algorithm`

        names = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU, "elu": torch.nn.ELU}
        names["leaky_relu"] = torch.nn.LeakyReLU
        policy_kwargs["activation_fn"] = names[policy_kwargs["activation_fn"]]
    if policy_kwargs:
        kwargs["policy_kwargs"] = policy_kwargs
    if kwargs.get("replay_buffer_class") == "HerReplayBuffer":
        from stable_baselines3 import HerReplayBuffer  # as in `algorithm`

        kwargs["replay_buffer_class"] = HerReplayBuffer
    return kwargs
