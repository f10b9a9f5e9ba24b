"""Small frame helpers shared by every stage (numpy only)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["rotate", "yaw_of"]


def yaw_of(quaternion: Sequence[float] | NDArray[np.float64]) -> float:
    """Rotation about z of a quaternion (x, y, z, w), radians in (-π, π]."""
    x, y, z, w = (float(v) for v in quaternion)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def rotate(points: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Points turned counter-clockwise by ``angle`` radians about the origin, (N, 2)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(points, dtype=float) @ np.array([[c, s], [-s, c]])
