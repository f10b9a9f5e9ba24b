"""Gymnasium environments: one class for every grasp task, registered by id.

The class is imported lazily, so registering the ids (at ``import graspenv``) does
not load PyBullet.
"""

from __future__ import annotations

from typing import Any

from graspenv.envs.steps import EPISODE_STEPS

__all__ = ["EPISODE_STEPS", "GraspEnv", "load_env_config"]


def __getattr__(name: str) -> Any:
    if name in ("GraspEnv", "load_env_config"):
        from graspenv.envs import grasp_env

        return getattr(grasp_env, name)
    raise AttributeError(f"module 'graspenv.envs' has no attribute {name!r}")
