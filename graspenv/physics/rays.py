"""Vertical ray casts: what lies under a point, and where a particle comes to rest.

:class:`RayCaster` casts Bullet's batched rays onto the table and the objects
(particles are transparent to them) for the world's queries:
``PhysicsWorld.ray_heights`` (the surface under each point),
``PhysicsWorld.put_down`` (the highest surface under a new particle's disc)
and, every frame, the rest height of each raised bottom particle
(:data:`SUPPORT_CLEARANCE` says which surfaces count as its support).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pybullet as pb
from numpy.typing import NDArray

from graspenv.physics.bodies import SceneBodies
from graspenv.physics.pool import OBJECT_GROUP, STATIC_GROUP
from graspenv.physics.reports import RayHits

__all__ = ["MIN_SLOPE", "SUPPORT_CLEARANCE", "RayCaster"]

_RAY_BATCH = 8192
#: A bottom particle rests on a surface that its rays meet at least this many radii
#: below its centre. A ray from 0.9 radius out of a particle pressed into an object's
#: side can start inside the object (a convex hull), and Bullet reports a hit at its
#: very start; counting that as a support raised the particle's resting height with
#: it, so nothing pulled it down and the squeeze walked it up the side (docs/accuracy.md,
#: "Accuracy across the grasp space": the slide's box tipped 9° and lost its grip).
#: A particle on a top face's edge meets the face 0.44 radius below its centre or
#: lower.
SUPPORT_CLEARANCE = 0.1
#: A support tilted less than this (dz per metre across) is taken as level: over the
#: few millimetres a particle crosses in a frame it rises by less than the
#: tolerance it may sit above its support (``REST_TOLERANCE``, 0.2 mm, over 4 mm).
MIN_SLOPE = 0.05
# Rays start this far above the highest point any object could reach while resting.
_RAY_CLEARANCE = 0.5


class RayCaster:
    """Vertical rays down onto the table and the objects of one built scene.

    Args:
        client: the PyBullet client.
        bodies: the scene's bodies (the table's hits count as height 0).
        particle_radius: the particles' radius, metres: a particle's disc is its
            centre and four points 0.9 radius around it.
    """

    def __init__(self, client: int, bodies: SceneBodies, particle_radius: float) -> None:
        self._client = client
        self._bodies = bodies
        ring = 0.9 * particle_radius
        self._radius = particle_radius
        self._disc_width = 2.0 * ring  # between opposite rays of the ring
        self._disc_offsets = np.array(
            [
                [0.0, 0.0, 0.0],
                [ring, 0.0, 0.0],
                [-ring, 0.0, 0.0],
                [0.0, ring, 0.0],
                [0.0, -ring, 0.0],
            ]
        )

    def top(self) -> float:
        """Height rays start from, metres: above every object's bounding box."""
        tops = [0.0]
        for body in self._bodies.objects:
            _, high = pb.getAABB(body, physicsClientId=self._client)
            tops.append(high[2])
        return max(tops) + _RAY_CLEARANCE

    def _cast(
        self, starts: NDArray[np.float64], ends: NDArray[np.float64]
    ) -> Iterator[tuple[int, Any]]:
        """(row, Bullet's hit) of every ray from ``starts`` to ``ends`` (metres, world
        frame, shape (n, 3)), cast ``_RAY_BATCH`` at a time."""
        for lo in range(0, starts.shape[0], _RAY_BATCH):
            hits = pb.rayTestBatch(
                starts[lo : lo + _RAY_BATCH].tolist(),
                ends[lo : lo + _RAY_BATCH].tolist(),
                collisionFilterMask=OBJECT_GROUP | STATIC_GROUP,
                physicsClientId=self._client,
            )
            yield from enumerate(hits, start=lo)

    def heights(self, points: NDArray[np.float64]) -> RayHits:
        """The first surface under each point from above, and the object hit.

        Args:
            points: metres, world frame, shape (N, 2).
        """
        n = points.shape[0]
        height = np.zeros(n)
        hit_object = np.full(n, -1, dtype=np.int64)
        if n == 0:
            return RayHits(height, hit_object)
        top = self.top()
        starts = np.column_stack([points, np.full(n, top)])
        # Ending just under the table top keeps rays short (fewer broadphase visits).
        ends = np.column_stack([points, np.full(n, -1e-3)])
        table = self._bodies.table
        object_of_body = self._bodies.object_of_body
        for i, hit in self._cast(starts, ends):
            body = hit[0]
            if body < 0 or body == table:
                continue
            height[i] = hit[3][2]
            hit_object[i] = object_of_body.get(body, -1)
        return RayHits(height, hit_object)

    def support_heights(
        self, points: NDArray[np.float64], clearance: float = 0.0, fit_under: bool = False
    ) -> NDArray[np.float64]:
        """Height of the highest surface below each particle's disc (0: table), (n,).

        Rays go down from the centre and from four points 0.9 radius around it, so
        a particle whose centre has just passed an edge still counts as resting on
        it (pulling it down there would drive it into the edge and kick the object).
        A surface met less than ``clearance`` below a ray's start is not a support
        (:data:`SUPPORT_CLEARANCE`).

        Args:
            points: where the rays start from, metres, world frame, shape (n, 3).
            clearance: metres.
            fit_under: a particle lowered from above onto the table, beside an
                object that overhangs it, rests on the table (:meth:`_drop_overhangs`).
        """
        return self.support_planes(points, clearance, fit_under)[0]

    def support_planes(
        self, points: NDArray[np.float64], clearance: float = 0.0, fit_under: bool = False
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`support_heights` and the slope of the surface under each disc.

        The slope (dz/dx, dz/dy) is the difference of the opposite rays' heights
        over the disc's width where all five rays meet the same object and it tilts
        by more than :data:`MIN_SLOPE`; elsewhere (the table, an edge, a flat top) it
        is 0. Every object is convex, so the plane through the highest hit with that
        slope lies on or above the surface along a particle's path across it: a
        support followed along the plane is never inside the object.

        Args:
            points: where the rays start from, metres, world frame, shape (n, 3).
            clearance: metres.
            fit_under: as for :meth:`support_heights`.

        Returns:
            Heights, metres, (n,), and slopes, (n, 2).
        """
        n = points.shape[0]
        if n == 0:
            return np.zeros(0), np.zeros((0, 2))
        starts = (points[:, None, :] + self._disc_offsets[None, :, :]).reshape(-1, 3)
        ends = starts.copy()
        ends[:, 2] = -1e-3
        height = np.zeros(starts.shape[0])
        body = np.full(starts.shape[0], -1, dtype=np.int64)
        table = self._bodies.table
        for i, hit in self._cast(starts, ends):
            if hit[0] >= 0 and hit[0] != table and hit[3][2] <= starts[i, 2] - clearance:
                height[i] = hit[3][2]
                body[i] = hit[0]
        if fit_under:
            self._drop_overhangs(starts, height, body)
        height = height.reshape(n, -1)
        body = body.reshape(n, -1)
        slope = (height[:, [1, 3]] - height[:, [2, 4]]) / self._disc_width
        one_object = (body[:, 0] >= 0) & np.all(body == body[:, :1], axis=1)
        tilted = np.hypot(slope[:, 0], slope[:, 1]) > MIN_SLOPE
        slope[~(one_object & tilted)] = 0.0
        return height.max(axis=1), slope

    def _drop_overhangs(
        self, starts: NDArray[np.float64], height: NDArray[np.float64], body: NDArray[np.int64]
    ) -> None:
        """Forget (in place) the hits of each disc that fits under what they meet.

        For particles put down from above (:meth:`PhysicsWorld.put_down`). A ray
        down past a ball's equator meets its flank, but the ball overhangs the table
        there: a particle on the table under it touches nothing, and put on the
        flank it slid down between ball and table and spun the ball (docs/stability.md,
        "Stability on hard cases"). Rays up from the table to the hits measure the
        gap under them: where every ray of a disc that meets an object has at least
        a particle's diameter under it, the particle fits under and those hits are
        no support. Under a box or a cylinder resting on the table a ray starts
        inside and the gap is 0; under the raised side of a tipped one a particle
        goes on the table only where it fits, as beside a ball. A particle already
        resting on an object keeps it as its support even when the object is in the
        air (tipped, or knocked up): its rays start at it.

        Args:
            starts: the disc rays' starts, (5 n, 3), five rows a disc.
            height, body: their hits' heights and bodies (-1: the table), (5 n,).
        """
        rows = np.flatnonzero(body >= 0)
        if rows.size == 0:
            return
        ends = starts[rows].copy()
        ends[:, 2] = height[rows]
        bottoms = ends.copy()
        bottoms[:, 2] = 0.0
        gap = np.full(height.shape, np.inf)
        table = self._bodies.table
        for k, hit in self._cast(bottoms, ends):
            gap[rows[k]] = hit[3][2] if hit[0] >= 0 and hit[0] != table else height[rows[k]]
        fits = np.all(gap.reshape(-1, len(self._disc_offsets)) >= 2.0 * self._radius, axis=1)
        under = np.repeat(fits, len(self._disc_offsets))
        height[under] = 0.0
        body[under] = -1
