"""Polygons: any simple polygon pressed onto the table, such as a card.

:class:`PolygonShape` is a :class:`~graspenv.surface.contact_shape.ContactShape`
built from its vertices (checked to be simple: no edges crossing or touching).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.geometry import shoelace
from graspenv.surface import _checks
from graspenv.surface.contact_shape import BoolArray, ContactShape, FloatArray

__all__ = ["PolygonShape"]


def _edges_cross(vertices: FloatArray) -> bool:
    """Whether two non-adjacent edges of the closed polygon touch or cross."""
    m = len(vertices)
    if m < 4:
        return False
    p, q = vertices, np.roll(vertices, -1, axis=0)

    def orient(a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray:
        result: FloatArray = np.sign(
            (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        )
        return result

    i, j = np.triu_indices(m, k=2)
    keep = ~((i == 0) & (j == m - 1))  # the first and last edges share a vertex
    i, j = i[keep], j[keep]
    pi, qi, pj, qj = p[i], q[i], p[j], q[j]
    d1, d2 = orient(pi, qi, pj), orient(pi, qi, qj)
    d3, d4 = orient(pj, qj, pi), orient(pj, qj, qi)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)

    def within(a: FloatArray, b: FloatArray, c: FloatArray) -> NDArray[np.bool_]:
        """Whether c, known to lie on the line ab, lies on the segment ab."""
        result: NDArray[np.bool_] = np.all(
            (np.minimum(a, b) <= c) & (c <= np.maximum(a, b)), axis=1
        )
        return result

    # A vertex lying on another edge breaks simplicity as much as a crossing does.
    touching = (
        ((d1 == 0) & within(pi, qi, pj))
        | ((d2 == 0) & within(pi, qi, qj))
        | ((d3 == 0) & within(pj, qj, pi))
        | ((d4 == 0) & within(pj, qj, qi))
    )
    return bool(np.any(proper | touching))


class PolygonShape(ContactShape):
    """Any simple polygon, such as a card lying on the table.

    Args:
        vertices: metres, local frame (relative to the centre, before turning by
            ``angle``), shape (M, 2), M >= 3, either orientation, not closed (the last
            vertex is joined to the first), no edges crossing.
        centre: metres, world frame, shape (2,).
        angle: radians.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s.

    Raises:
        ValueError: fewer than 3 vertices, repeated consecutive vertices, zero area,
            crossing edges, or non-finite values.
    """

    def __init__(
        self,
        vertices: ArrayLike,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        super().__init__(centre, angle, linear_velocity, angular_velocity)
        local = np.array(_checks.points(vertices, "vertices"))
        if len(local) < 3:
            raise ValueError(f"vertices must hold at least 3 points, got {len(local)}")
        steps = np.hypot(*(np.roll(local, -1, axis=0) - local).T)
        if np.any(steps == 0.0):
            raise ValueError("vertices must not repeat consecutively (zero-length edge)")
        area = shoelace(local)
        if area == 0.0:
            raise ValueError("vertices enclose zero area")
        if _edges_cross(local):
            raise ValueError("vertices must form a simple polygon; two edges cross or touch")
        self._vertices = local if area > 0.0 else local[::-1].copy()
        self._area = abs(area)

    @classmethod
    def rectangle(
        cls,
        size: ArrayLike,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
    ) -> PolygonShape:
        """A rectangle of full ``size`` (width along local x, height along local y),
        metres, centred on ``centre`` (metres, world frame, shape (2,))."""
        full = _checks.vector2(size, "size")
        if np.any(full <= 0.0):
            raise ValueError(f"size must be > 0 metres, got {full.tolist()}")
        hx, hy = 0.5 * full
        return cls([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]], centre, angle)

    @classmethod
    def from_world(cls, vertices: ArrayLike) -> PolygonShape:
        """A polygon from world vertices (metres, shape (M, 2)); its centre is the area
        centroid and its angle 0."""
        world = _checks.points(vertices, "vertices")
        if len(world) < 3:
            raise ValueError(f"vertices must hold at least 3 points, got {len(world)}")
        origin = world.mean(axis=0)
        relative = world - origin
        x, y = relative[:, 0], relative[:, 1]
        x1, y1 = np.roll(x, -1), np.roll(y, -1)
        cross = x * y1 - x1 * y
        area = 0.5 * float(np.sum(cross))
        if area == 0.0:
            raise ValueError("vertices enclose zero area")
        centroid = origin + np.array([np.sum((x + x1) * cross), np.sum((y + y1) * cross)]) / (
            6.0 * area
        )
        return cls(world - centroid, centroid)

    def _parameters(self) -> str:
        return f"vertices={self._vertices.round(6).tolist()}"

    @property
    def vertices(self) -> FloatArray:
        """Counter-clockwise vertices, metres, local frame, shape (M, 2) (a copy)."""
        return self._vertices.copy()

    @property
    def area(self) -> float:
        return self._area

    @property
    def bounding_radius(self) -> float:
        return float(np.hypot(*self._vertices.T).max())

    def _local_outline(self, max_segment: float) -> FloatArray:
        start = self._vertices
        edge = np.roll(start, -1, axis=0) - start
        counts = np.ceil(np.hypot(*edge.T) / max_segment).astype(int)
        owner = np.repeat(np.arange(len(start)), counts)
        offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        fraction = offsets / counts[owner]
        result: FloatArray = start[owner] + edge[owner] * fraction[:, None]
        return result

    def _local_contains(self, local: FloatArray) -> BoolArray:
        distance = self._edge_distance(local)
        # On an edge counts as inside, as for the other shapes.
        result: BoolArray = self._crossing_parity(local) | (distance == 0.0)
        return result

    def _local_signed_distance(self, local: FloatArray) -> FloatArray:
        distance = self._edge_distance(local)
        return np.where(self._crossing_parity(local), -distance, distance)

    def _crossing_parity(self, local: FloatArray) -> BoolArray:
        a = self._vertices[None, :, :]
        b = np.roll(self._vertices, -1, axis=0)[None, :, :]
        px, py = local[:, None, 0], local[:, None, 1]
        straddles = (a[..., 1] > py) != (b[..., 1] > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = a[..., 0] + (py - a[..., 1]) * (b[..., 0] - a[..., 0]) / (
                b[..., 1] - a[..., 1]
            )
        crossings = straddles & (px < x_cross)
        result: BoolArray = np.count_nonzero(crossings, axis=1) % 2 == 1
        return result

    def _edge_distance(self, local: FloatArray) -> FloatArray:
        a = self._vertices[None, :, :]
        edge = np.roll(self._vertices, -1, axis=0)[None, :, :] - a
        rel = local[:, None, :] - a
        t = np.clip(np.sum(rel * edge, axis=2) / np.sum(edge * edge, axis=2), 0.0, 1.0)
        gap = rel - t[..., None] * edge
        result: FloatArray = np.hypot(gap[..., 0], gap[..., 1]).min(axis=1)
        return result
