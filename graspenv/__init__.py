"""graspenv: grasping on an imaging touch table, simulated with persistent particle
proxies (Wilson, ITS 2009) in PyBullet, as Gymnasium environments."""

from __future__ import annotations

from graspenv.config import ConfigError, SceneConfig, load_config

__version__ = "0.1.0"

# Environment ids are registered here once the environment suite lands.
ENV_IDS: tuple[str, ...] = ()

__all__ = ["ENV_IDS", "ConfigError", "SceneConfig", "__version__", "load_config"]
