"""Colours and cheap visual shapes for the headless 3-D view of a PhysicsWorld
(:meth:`~graspenv.physics.world.PhysicsWorld.render`).

Images come from Bullet's software TinyRenderer (``ER_TINY_RENDERER``): it needs no
GUI, display or EGL, so it works in DIRECT mode on any machine. It draws every
visual shape of every body, whether in view or not, so particles get a 20-triangle
icosahedron instead of Bullet's default sphere mesh: 640 parked particles then add
about 4 ms to a 320 × 240 image instead of about 12 ms.

Bodies created without a visual shape would be drawn from their collision shape in
white; everything here gets a colour so that table, objects and fingers stand apart.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "FLOOR_RGBA",
    "OBJECT_RGBA",
    "PARTICLE_RGBA",
    "RIGID_PROXY_RGBA",
    "TABLE_RGBA",
    "icosahedron",
    "object_rgba",
]

#: Colours (red, green, blue, alpha in [0, 1]).
TABLE_RGBA = (0.70, 0.74, 0.80, 1.0)
FLOOR_RGBA = (0.30, 0.30, 0.32, 1.0)
#: Fingers: particles and rigid proxy bodies alike.
PARTICLE_RGBA = (0.85, 0.15, 0.15, 1.0)
RIGID_PROXY_RGBA = PARTICLE_RGBA
#: Objects take these in ``scene.objects`` order, cycling.
OBJECT_RGBA = (
    (0.95, 0.55, 0.10, 1.0),
    (0.20, 0.45, 0.90, 1.0),
    (0.20, 0.70, 0.30, 1.0),
    (0.60, 0.30, 0.75, 1.0),
    (0.95, 0.85, 0.20, 1.0),
)


def object_rgba(index: int) -> tuple[float, float, float, float]:
    """Colour of the object at ``index`` in ``scene.objects``."""
    return OBJECT_RGBA[index % len(OBJECT_RGBA)]


def icosahedron(radius: float) -> tuple[list[list[float]], list[int]]:
    """A regular icosahedron around the origin: a sphere in 20 triangles.

    Args:
        radius: distance from the centre to each vertex, metres.

    Returns:
        (vertices, indices): 12 vertices (x, y, z) in metres and 60 vertex indices,
        three per triangle, counter-clockwise seen from outside.
    """
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = np.array(
        [
            [-1, t, 0],
            [1, t, 0],
            [-1, -t, 0],
            [1, -t, 0],
            [0, -1, t],
            [0, 1, t],
            [0, -1, -t],
            [0, 1, -t],
            [t, 0, -1],
            [t, 0, 1],
            [-t, 0, -1],
            [-t, 0, 1],
        ],
        dtype=float,
    )
    vertices *= radius / math.sqrt(1.0 + t * t)
    faces = [
        (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11),
        (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
        (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
        (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1),
    ]  # fmt: skip
    return vertices.tolist(), [i for face in faces for i in face]
