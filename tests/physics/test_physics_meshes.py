"""Mesh shapes: built from vertex lists without PyBullet's reference leak."""

from __future__ import annotations

import tracemalloc
from collections.abc import Callable

import numpy as np

from graspenv.physics import PhysicsWorld
from graspenv.physics.meshes import mesh_collision_shape, mesh_visual_shape
from graspenv.physics.view import icosahedron


def _python_bytes_kept(make: Callable[[int], object], calls: int) -> int:
    """Python memory still allocated after ``calls`` calls of ``make(i)``, bytes."""
    tracemalloc.start()
    try:
        make(0)
        before = tracemalloc.get_traced_memory()[0]
        for i in range(1, calls + 1):
            make(i)
        return tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()


def test_mesh_shapes_keep_no_python_objects(world: PhysicsWorld) -> None:
    client = world.client
    a = np.linspace(0.0, 2 * np.pi, 20, endpoint=False)

    def prism(i: int) -> np.ndarray:
        ring = np.column_stack([0.008 * np.cos(a + 1e-4 * i), 0.008 * np.sin(a), np.zeros(20)])
        return np.concatenate([ring, ring + np.array([0.0, 0.0, 0.01])])

    # Plain PyBullet keeps every vertex list: about 7 KB per call here, 3.5 MB in all.
    kept = _python_bytes_kept(lambda i: mesh_collision_shape(client, prism(i)), 500)
    assert kept < 50_000
    vertices, indices = icosahedron(0.002)
    kept = _python_bytes_kept(
        lambda i: mesh_visual_shape(
            client, np.asarray(vertices) * (1 + 1e-6 * i), indices, (1.0, 0.0, 0.0, 1.0)
        ),
        500,
    )
    assert kept < 50_000


def test_icosahedron_is_a_closed_outward_mesh() -> None:
    vertices, indices = icosahedron(0.003)
    v = np.asarray(vertices)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 0.003)
    triangles = v[np.asarray(indices).reshape(-1, 3)]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    # Counter-clockwise seen from outside: every normal points away from the centre.
    assert np.all(np.einsum("ij,ij->i", normals, triangles.mean(axis=1)) > 0)
    assert len(indices) == 60
