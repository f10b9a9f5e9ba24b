"""Mesh shapes from vertex lists, without PyBullet's reference leak.

PyBullet 3.2.x leaks two references to the ``vertices`` sequence, to each of its
rows and to the ``indices`` sequence of every mesh it builds from Python lists
(``createCollisionShape`` / ``createVisualShape`` with ``GEOM_MESH``), so every
vertex list ever passed stays in memory: about 4 KB per rigid proxy touch-down, and
a particle pool's mesh on every scene rebuild. The calls here hand PyBullet fresh
lists that nothing else holds, count the references they gained across the call
and give back exactly that many. Bullet copies the numbers into its own arrays and
keeps no Python object, so the extra references can only be the leak; a PyBullet
that no longer leaks gains none and nothing is given back.
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable, Sequence

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike

__all__ = ["mesh_collision_shape", "mesh_visual_shape"]

_decref = ctypes.pythonapi.Py_DecRef
_decref.argtypes = [ctypes.py_object]
_decref.restype = None


def mesh_collision_shape(client: int, vertices: ArrayLike) -> int:
    """A convex collision shape: the hull of the vertices.

    Args:
        client: PyBullet client id.
        vertices: metres, in the body's frame, shape (V, 3).

    Returns:
        The collision shape index.
    """
    rows = np.asarray(vertices, dtype=float).reshape(-1, 3).tolist()
    return _call_giving_back_leaks(
        lambda: pb.createCollisionShape(pb.GEOM_MESH, vertices=rows, physicsClientId=client),
        [rows, *rows],
    )


def mesh_visual_shape(
    client: int,
    vertices: ArrayLike,
    indices: Sequence[int],
    rgba: tuple[float, float, float, float],
) -> int:
    """A triangle-mesh visual shape.

    Args:
        client: PyBullet client id.
        vertices: metres, in the body's frame, shape (V, 3).
        indices: three vertex indices per triangle, counter-clockwise seen from
            outside, length 3·T.
        rgba: colour, each in [0, 1].

    Returns:
        The visual shape index.
    """
    rows = np.asarray(vertices, dtype=float).reshape(-1, 3).tolist()
    corners = [int(i) for i in indices]
    return _call_giving_back_leaks(
        lambda: pb.createVisualShape(
            pb.GEOM_MESH,
            vertices=rows,
            indices=corners,
            rgbaColor=rgba,
            physicsClientId=client,
        ),
        [rows, *rows, corners],
    )


def _call_giving_back_leaks(call: Callable[[], int], owned: list[object]) -> int:
    """Run ``call`` and drop the references it gained to ``owned`` objects.

    Every object in ``owned`` must be referenced only by the caller's locals (and
    this list), so that any reference gained during the call is a leaked one.
    """
    before = [sys.getrefcount(obj) for obj in owned]
    result = call()
    for obj, count in zip(owned, before, strict=True):
        for _ in range(sys.getrefcount(obj) - count):
            _decref(obj)
    return int(result)
