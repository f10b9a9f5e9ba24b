"""graspenv: grasping on an imaging touch table, simulated with persistent particle
proxies (Wilson, ITS 2009) in PyBullet, as Gymnasium environments."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from graspenv.config import ConfigError, SceneConfig, load_config

if TYPE_CHECKING:
    from graspenv.simulation import Simulation

__version__ = "0.1.0"

# Environment ids are registered here once the environment suite lands.
ENV_IDS: tuple[str, ...] = ()


def make_simulation(
    config: str | Path | dict[str, Any] | SceneConfig | None = None, **overrides: Any
) -> Simulation:
    """Build a :class:`~graspenv.simulation.Simulation` for users who bring their own
    masks; see :func:`graspenv.simulation.make_simulation`."""
    # Imported here so `import graspenv` stays light (no PyBullet until needed).
    from graspenv.simulation import make_simulation as make

    return make(config, **overrides)


__all__ = [
    "ENV_IDS",
    "ConfigError",
    "SceneConfig",
    "__version__",
    "load_config",
    "make_simulation",
]
