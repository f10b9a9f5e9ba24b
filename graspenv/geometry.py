"""Small frame helpers shared by every stage (numpy only)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["rotate", "tilt_angle", "yaw_of"]


def yaw_of(quaternion: Sequence[float] | NDArray[np.float64]) -> float:
    """Rotation about z of a quaternion (x, y, z, w), radians in (-π, π]."""
    x, y, z, w = (float(v) for v in quaternion)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def rotate(points: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Points turned counter-clockwise by ``angle`` radians about the origin, (N, 2)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(points, dtype=float) @ np.array([[c, s], [-s, c]])


def tilt_angle(quaternion: Sequence[float] | NDArray[np.float64]) -> float:
    """Angle between a body's z axis and the world's z axis.

    Args:
        quaternion: orientation (x, y, z, w), normalised here, shape (4,).

    Returns:
        Radians in [0, π]; yaw alone gives 0.
    """
    x, y, z, w = np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion)
    # Third column of the rotation matrix: the body's z axis in the world frame.
    axis_x = 2.0 * (x * z + w * y)
    axis_y = 2.0 * (y * z - w * x)
    axis_z = 1.0 - 2.0 * (x * x + y * y)
    return math.atan2(math.hypot(axis_x, axis_y), axis_z)
