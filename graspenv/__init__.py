"""graspenv: grasping on an imaging touch table, simulated with persistent particle
proxies (Wilson, ITS 2009) in PyBullet, as Gymnasium environments."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from graspenv.config import ConfigError, SceneConfig, load_config

if TYPE_CHECKING:
    from graspenv.simulation import Simulation

__version__ = "0.1.0"

#: The registered environment ids (``gym.make(id)``), one per task.
ENV_IDS: tuple[str, ...] = (
    "graspenv/SqueezeHold-v0",
    "graspenv/TurnInPlace-v0",
    "graspenv/SqueezeSlide-v0",
    "graspenv/SidePush-v0",
    "graspenv/TopRub-v0",
    "graspenv/CatchBall-v0",
)


def _register() -> None:
    # Registration needs no PyBullet: the entry point is a string, imported by
    # gym.make; the episode lengths live beside the environment class.
    import gymnasium as gym

    from graspenv.envs.steps import EPISODE_STEPS

    for env_id in ENV_IDS:
        if env_id in gym.registry:
            continue
        task = env_id.split("/")[1].split("-")[0]
        gym.register(
            id=env_id,
            entry_point="graspenv.envs.grasp_env:make_grasp_env",
            kwargs={"task": task},
            max_episode_steps=EPISODE_STEPS[task],
        )


_register()


def make_simulation(
    config: str | Path | dict[str, Any] | SceneConfig | None = None,
    *,
    fidelity: str = "default",
    error_budget: float | None = None,
    **overrides: Any,
) -> Simulation:
    """Build a :class:`~graspenv.simulation.Simulation` for users who bring their own
    masks, at one of the environments' fidelity presets; see
    :func:`graspenv.simulation.make_simulation`."""
    # Imported here so `import graspenv` stays light (no PyBullet until needed).
    from graspenv.simulation import make_simulation as make

    return make(config, fidelity=fidelity, error_budget=error_budget, **overrides)


__all__ = [
    "ENV_IDS",
    "ConfigError",
    "SceneConfig",
    "__version__",
    "load_config",
    "make_simulation",
]
