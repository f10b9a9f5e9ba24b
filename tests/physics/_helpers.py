"""Shared by the physics tests: two ideal round fingertips that squeeze the default
scene's box and turn it, driven straight through ``PhysicsWorld.step_frame``."""

from __future__ import annotations

import math

import numpy as np

from graspenv.geometry import yaw_of
from graspenv.physics import PhysicsWorld

# The default scene's box: 6 × 6 × 3 cm, centred at the origin.
BOX_HALF = 0.03
BOX_HEIGHT = 0.03


def _finger(centre: np.ndarray, angle: float, n: int = 14, radius: float = 0.0075) -> np.ndarray:
    a = angle + 2 * math.pi * np.arange(n) / n
    return centre + radius * np.column_stack([np.cos(a), np.sin(a)])


def _smooth(s: float) -> float:
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def squeeze_and_turn(world: PhysicsWorld) -> tuple[float, np.ndarray]:
    """Two round fingertips squeeze the box 3 mm deep and turn 90° about it in 1.5 s,
    then hold a quarter of a second; the box's yaw (degrees) and position after."""
    r = world.scene.proxy.particle_radius
    start, squeeze = BOX_HALF + 0.0075 + 0.004, BOX_HALF + 0.0075 - 0.003
    sides = (np.array([1.0, 0.0]), np.array([-1.0, 0.0]))
    ids = world.pool.acquire(28)
    pts = np.concatenate([_finger(s * start, 0.0) for s in sides])
    world.pool.place(ids, np.column_stack([pts, np.full(28, r)]))

    def targets(d: float, theta: float) -> np.ndarray:
        rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
        return np.concatenate([_finger(rot @ (s * d), theta) for s in sides])

    for f in range(1, 16):
        world.step_frame(ids, targets(start + (squeeze - start) * _smooth(f / 15), 0.0))
    theta = 0.0
    for f in range(1, 106):
        new = math.pi / 2 * _smooth(min(f / 90, 1.0))
        world.step_frame(ids, targets(squeeze, new), spin=(new - theta) / world.frame_dt)
        theta = new
    position, q = world.object_pose("box")
    return math.degrees(yaw_of(q)), position
