"""The headless 3-D view of a PhysicsWorld
(:meth:`~graspenv.physics.world.PhysicsWorld.render`): its camera, colours and cheap
visual shapes.

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
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "FLOOR_RGBA",
    "OBJECT_RGBA",
    "PARTICLE_RGBA",
    "RIGID_PROXY_RGBA",
    "TABLE_RGBA",
    "icosahedron",
    "object_rgba",
    "render_view",
]

# The camera of :func:`render_view`. Nearest distance it draws, metres: well
# under any sensible view distance.
_NEAR = 0.01
# The far plane lies this far beyond the target: the whole floor (4 m across) is in
# range, parked particles (more than a kilometre away) never are.
_FAR_BEYOND_TARGET = 10.0

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


def render_view(
    client: int,
    size: tuple[int, int],
    target: ArrayLike,
    orbit: tuple[float, float, float],
    fov: float,
) -> NDArray[np.uint8]:
    """A 3-D view of Bullet client ``client``'s bodies, ``size`` (width, height)
    pixels, the camera at ``orbit`` (distance, yaw, pitch) about ``target``: the
    arguments, the image and the errors are
    :meth:`~graspenv.physics.world.PhysicsWorld.render`'s."""
    width, height = size
    distance, yaw_deg, pitch_deg = orbit
    if int(width) != width or int(height) != height or width < 1 or height < 1:
        raise ValueError(f"render needs a positive integer width and height, got {width}×{height}")
    point = np.asarray(target, dtype=float)
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        raise ValueError(f"render target must be 3 finite numbers (metres), got {target!r}")
    if not distance > 0.0:
        raise ValueError(f"render distance must be > 0 metres, got {distance}")
    if not 0.0 < fov < 180.0:
        raise ValueError(f"render fov must be in (0, 180) degrees, got {fov}")
    w, h = int(width), int(height)
    view = pb.computeViewMatrixFromYawPitchRoll(
        cameraTargetPosition=point.tolist(),
        distance=float(distance),
        yaw=float(yaw_deg),
        pitch=float(pitch_deg),
        roll=0.0,
        upAxisIndex=2,
        physicsClientId=client,
    )
    projection = pb.computeProjectionMatrixFOV(
        fov=float(fov),
        aspect=w / h,
        nearVal=_NEAR,
        farVal=float(distance) + _FAR_BEYOND_TARGET,
        physicsClientId=client,
    )
    _, _, rgba, _, _ = pb.getCameraImage(
        w,
        h,
        viewMatrix=view,
        projectionMatrix=projection,
        renderer=pb.ER_TINY_RENDERER,
        physicsClientId=client,
    )
    # PyBullet returns an ndarray when built with numpy, a flat list otherwise.
    image = np.asarray(rgba, dtype=np.uint8).reshape(h, w, 4)
    return np.ascontiguousarray(image[:, :, :3])
