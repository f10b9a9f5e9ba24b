"""A picture of every environment, for the README (``graspenv gallery``)."""

from __future__ import annotations

from pathlib import Path

import cv2
import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from graspenv.viz import contact_sheet, put_label

__all__ = ["gallery"]


def _snapshot(env_id: str, seed: int, steps: int) -> NDArray[np.uint8]:
    """The top-down view after the hand comes down and closes for a few steps."""
    env = gym.make(env_id, render_mode="rgb_array")
    try:
        env.reset(seed=seed)
        shape = env.action_space.shape
        assert shape is not None
        size = shape[0]
        # Grip mode: close and touch; fingers mode: move towards the table centre, down.
        action = np.zeros(size, np.float32)
        if size == 5:
            action[3], action[4] = -0.6, 1.0
        else:
            action[2::3] = 1.0
        for _ in range(steps):
            env.step(action)
        picture = np.asarray(env.render(), dtype=np.uint8)
    finally:
        env.close()
    return np.ascontiguousarray(picture[:, :, ::-1])  # RGB → BGR for OpenCV


def gallery(env_ids: tuple[str, ...], out: Path, seed: int = 0, steps: int = 8) -> Path:
    """Write a contact sheet of every environment's top-down view to ``out`` (PNG).

    The goal pose is drawn in green, the object in blue, particles in red and the
    fingertips as rings.
    """
    tiles = []
    for env_id in env_ids:
        tile = _snapshot(env_id, seed, steps)
        h, w = tile.shape[:2]
        # The middle of the table is where everything happens.
        tile = np.ascontiguousarray(tile[h // 6 : h - h // 6, w // 6 : w - w // 6])
        put_label(tile, env_id.removeprefix("graspenv/"))
        tiles.append(tile)
    out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(out), contact_sheet(tiles, columns=3)):
        raise OSError(f"could not write {out}")
    return out
