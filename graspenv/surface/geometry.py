"""The imaging surface's frames: world metres and camera pixels."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.config import SurfaceConfig

__all__ = ["Surface"]


@dataclass(frozen=True)
class Surface:
    """A camera-based touch table: its size, its camera resolution and frame rate.

    World frame: origin at the table centre, x to the right, y away from the viewer
    (up in the image), z up from the table top; metres. Pixel frame: (column, row),
    row 0 at the top of the image. Pixel (c, r) covers the square
    ``[c - 0.5, c + 0.5] × [r - 0.5, r + 0.5]`` in continuous pixel coordinates, so its
    centre is at the integer coordinates (c, r) and the image spans
    ``[-0.5, W - 0.5] × [-0.5, H - 0.5]``, which maps exactly onto the table top.

    Attributes:
        size: table (width, height), metres.
        resolution: image (W columns, H rows), pixels.
        fps: camera frames per second.
    """

    size: tuple[float, float] = (0.61, 0.46)
    resolution: tuple[int, int] = (640, 480)
    fps: float = 60.0

    @classmethod
    def from_config(cls, config: SurfaceConfig) -> Surface:
        return cls(size=config.size, resolution=config.resolution, fps=config.fps)

    @property
    def dt(self) -> float:
        """Seconds between two camera frames."""
        return 1.0 / self.fps

    @property
    def pixel_size(self) -> NDArray[np.float64]:
        """Metres per pixel along (x, y)."""
        return np.asarray(self.size, dtype=float) / np.asarray(self.resolution, dtype=float)

    @property
    def shape(self) -> tuple[int, int]:
        """Mask shape (H, W), as numpy and OpenCV index images."""
        return (self.resolution[1], self.resolution[0])

    def world_to_pixel(self, xy: ArrayLike) -> NDArray[np.float64]:
        """Continuous pixel coordinates (column, row) of world points.

        Args:
            xy: metres, world frame, shape (N, 2) (or (2,)).

        Returns:
            pixels (column, row), same shape; integers are pixel centres.
        """
        p = np.asarray(xy, dtype=float)
        w, h = self.size
        sx, sy = self.pixel_size
        col = (p[..., 0] + 0.5 * w) / sx - 0.5
        row = (0.5 * h - p[..., 1]) / sy - 0.5
        return np.stack([col, row], axis=-1)

    def pixel_to_world(self, px: ArrayLike) -> NDArray[np.float64]:
        """World points of continuous pixel coordinates; the exact inverse of
        :meth:`world_to_pixel`.

        Args:
            px: pixels (column, row), shape (N, 2) (or (2,)).

        Returns:
            metres, world frame, same shape.
        """
        q = np.asarray(px, dtype=float)
        w, h = self.size
        sx, sy = self.pixel_size
        x = (q[..., 0] + 0.5) * sx - 0.5 * w
        y = 0.5 * h - (q[..., 1] + 0.5) * sy
        return np.stack([x, y], axis=-1)

    def contains(self, xy: ArrayLike) -> NDArray[np.bool_]:
        """Whether world points (metres, shape (N, 2)) lie on the table top."""
        p = np.asarray(xy, dtype=float)
        half = 0.5 * np.asarray(self.size)
        return np.all(np.abs(p) <= half, axis=-1)
