"""World ↔ pixel transforms of the table."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from graspenv.config import SurfaceConfig
from graspenv.surface import Surface

sizes = st.tuples(st.floats(0.05, 3.0), st.floats(0.05, 3.0))
resolutions = st.tuples(st.integers(8, 4096), st.integers(8, 4096))


@settings(deadline=None, max_examples=60)
@given(
    size=sizes,
    resolution=resolutions,
    fractions=st.lists(st.tuples(st.floats(-1.0, 2.0), st.floats(-1.0, 2.0)), min_size=1),
)
def test_world_to_pixel_and_back_are_exact_inverses(
    size: tuple[float, float],
    resolution: tuple[int, int],
    fractions: list[tuple[float, float]],
) -> None:
    table = Surface(size=size, resolution=resolution)
    world = (np.array(fractions) - 0.5) * np.array(size)
    back = table.pixel_to_world(table.world_to_pixel(world))
    np.testing.assert_allclose(back, world, rtol=0, atol=1e-12 * max(size))
    pixels = np.array(fractions) * np.array(resolution)
    again = table.world_to_pixel(table.pixel_to_world(pixels))
    np.testing.assert_allclose(again, pixels, rtol=0, atol=1e-9 * max(resolution))


def test_pixel_centres_and_image_corners(surface: Surface) -> None:
    w, h = surface.size
    width, height = surface.resolution
    sx, sy = surface.pixel_size
    # The image's outer corners are the table's corners; row 0 is the far edge (y up).
    corners = surface.world_to_pixel([[-w / 2, h / 2], [w / 2, -h / 2]])
    np.testing.assert_allclose(corners, [[-0.5, -0.5], [width - 0.5, height - 0.5]], atol=1e-9)
    first = surface.pixel_to_world([[0.0, 0.0]])
    np.testing.assert_allclose(first, [[-w / 2 + sx / 2, h / 2 - sy / 2]], atol=1e-15)
    assert surface.shape == (height, width)


def test_surface_from_config_keeps_the_values() -> None:
    config = SurfaceConfig(size=(0.4, 0.3), resolution=(320, 240), fps=120.0)
    table = Surface.from_config(config)
    assert (table.size, table.resolution, table.fps) == ((0.4, 0.3), (320, 240), 120.0)
    assert table.dt == 1.0 / 120.0
