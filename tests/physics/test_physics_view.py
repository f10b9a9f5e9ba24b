"""PhysicsWorld.render: a headless 3-D view of the table, objects and particles."""

from __future__ import annotations

import numpy as np
import pytest

from graspenv.physics import PhysicsWorld

# Straight down onto the table centre (exactly -90 would leave the camera's up
# direction undefined). At 0.5 m and 50° the view spans about ±0.31 m in x and
# ±0.23 m in y: the table top with the default 6 cm box in the middle.
TOP = {"target": (0.0, 0.0, 0.0), "distance": 0.5, "yaw_deg": 0.0, "pitch_deg": -89.9}
W, H = 160, 120


def _pixel(x: float, y: float) -> tuple[int, int]:
    """Row and column of a table point in the TOP view (x right, y up the image)."""
    half_h = 0.5 * float(np.tan(np.radians(25.0)))
    half_w = half_h * W / H
    return round((0.5 - y / (2 * half_h)) * H), round((0.5 + x / (2 * half_w)) * W)


def test_render_shape_and_what_is_where(world: PhysicsWorld) -> None:
    image = world.render(W, H, **TOP)  # type: ignore[arg-type]
    assert image.shape == (H, W, 3) and image.dtype == np.uint8
    box = image[_pixel(0.0, 0.0)].astype(int)
    table = image[_pixel(0.15, 0.1)].astype(int)
    assert np.abs(box - table).sum() > 60
    assert box[0] > box[2] + 60  # the first object is orange, the table blue-grey

    # Active particles show (red) where they are; parked ones never do.
    ids = world.pool.acquire(200)
    world.pool.release(ids[100:])
    # A 10 × 10 block of touching particles, 4 cm across, around (-0.15, -0.1).
    xy = np.array([-0.168, -0.118]) + 0.004 * np.stack(np.divmod(np.arange(100), 10), axis=1)
    world.pool.place(ids[:100], np.column_stack([xy, np.full(100, world.pool.radius)]))
    with_particles = world.render(W, H, **TOP).astype(int)  # type: ignore[arg-type]
    row, col = _pixel(-0.15, -0.1)
    patch = with_particles[row - 3 : row + 4, col - 3 : col + 4].reshape(-1, 3)
    red = (patch[:, 0] > patch[:, 1] + 60) & (patch[:, 0] > patch[:, 2] + 60)
    assert np.count_nonzero(red) >= 15  # of 49; 4 mm spheres at 4 mm per pixel leave gaps
    world.pool.release(ids[:100])
    assert np.array_equal(world.render(W, H, **TOP), image)  # type: ignore[arg-type]


def test_render_from_the_side_sees_the_box_standing_up(world: PhysicsWorld) -> None:
    image = world.render(120, 90, (0.0, 0.0, 0.015), 0.3, yaw_deg=90.0, pitch_deg=-10.0)
    centre = image[45, 60].astype(int)
    above = image[5, 60].astype(int)  # over the box: the table or beyond it
    assert np.abs(centre - above).sum() > 60


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"width": 0}, "positive integer width"),
        ({"distance": 0.0}, "distance must be > 0"),
        ({"fov": 180.0}, r"fov must be in \(0, 180\)"),
        ({"target": (0.0, 0.0)}, "target must be 3 finite numbers"),
    ],
)
def test_render_refuses_bad_cameras(
    world: PhysicsWorld, kwargs: dict[str, object], message: str
) -> None:
    args: dict[str, object] = {"width": 32, "height": 24, **TOP, **kwargs}
    with pytest.raises(ValueError, match=message):
        world.render(**args)  # type: ignore[arg-type]
