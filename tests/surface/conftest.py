"""Fixtures for the surface tests: the default table and its pixel centres."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray

from graspenv.surface import Surface


@pytest.fixture(scope="session")
def surface() -> Surface:
    """The default 0.61 × 0.46 m table at 640 × 480 pixels and 60 frames per second."""
    return Surface()


@pytest.fixture(scope="session")
def pixel_centres(surface: Surface) -> NDArray[np.float64]:
    """World position of every pixel centre, metres, shape (H·W, 2), row-major."""
    height, width = surface.shape
    rows, cols = np.mgrid[0:height, 0:width]
    return surface.pixel_to_world(np.stack([cols.ravel(), rows.ravel()], axis=-1))


@pytest.fixture(scope="session")
def pixel(surface: Surface) -> float:
    """Mean pixel pitch, metres (pixels are within 0.5 % of square)."""
    return float(surface.pixel_size.mean())
