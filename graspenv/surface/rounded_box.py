"""Palms and hand edges: rectangles with rounded corners.

:class:`Palm` (the flat of a hand) and :class:`HandEdge` (the side of a hand laid
on the table) are both rounded rectangles
(:class:`~graspenv.surface.contact_shape.ContactShape`s) centred on the shape's
centre.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from graspenv.surface import _checks
from graspenv.surface.contact_shape import BoolArray, ContactShape, FloatArray

__all__ = ["HandEdge", "Palm"]


class _RoundedBox(ContactShape):
    """A rectangle with rounded corners, centred on the shape's centre."""

    def __init__(
        self,
        half_extents: ArrayLike,
        corner_radius: float,
        centre: ArrayLike,
        angle: float,
        linear_velocity: ArrayLike,
        angular_velocity: float,
    ) -> None:
        super().__init__(centre, angle, linear_velocity, angular_velocity)
        half = _checks.vector2(half_extents, "half_extents")
        if np.any(half <= 0.0):
            raise ValueError(f"sizes must be > 0 metres, got {(2.0 * half).tolist()}")
        radius = _checks.non_negative(corner_radius, "corner_radius")
        if radius > float(half.min()):
            raise ValueError(
                f"corner_radius must be at most half the smaller side "
                f"({float(half.min())} m), got {corner_radius!r}"
            )
        self._half = half
        self._radius = radius

    def _parameters(self) -> str:
        hx, hy = self._half
        return f"size=({2 * hx:.6g}, {2 * hy:.6g}), corner_radius={self._radius:.6g}"

    @property
    def area(self) -> float:
        hx, hy = self._half
        return float(4.0 * hx * hy - (4.0 - math.pi) * self._radius**2)

    @property
    def bounding_radius(self) -> float:
        core = self._half - self._radius
        return float(np.hypot(*core) + self._radius)

    def _local_outline(self, max_segment: float) -> FloatArray:
        r = self._radius
        ax, ay = self._half - r
        # Eight pieces counter-clockwise from the top-right corner: arc, top side, arc,
        # left side, ... Each is sampled from its start, so sharp corners (r = 0) and
        # the ends of the sides are vertices.
        corner = np.array([[ax, ay], [-ax, ay], [-ax, -ay], [ax, -ay]])
        quarter = 0.5 * math.pi
        lengths = np.array([quarter * r, 2 * ax, quarter * r, 2 * ay] * 2)
        counts = np.ceil(lengths / max_segment).astype(int)
        piece = np.repeat(np.arange(8), counts)
        fraction = (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)) / (
            counts[piece]
        )
        which = piece // 2
        angle = quarter * (which + np.where(piece % 2 == 0, fraction, 1.0))
        on_circle = corner[which] + r * np.stack([np.cos(angle), np.sin(angle)], axis=-1)
        # Along a side the point slides from corner k's circle to corner k+1's.
        slide = (corner[(which + 1) % 4] - corner[which]) * fraction[:, None]
        result: FloatArray = np.where((piece % 2 == 0)[:, None], on_circle, on_circle + slide)
        return result

    def _local_signed_distance(self, local: FloatArray) -> FloatArray:
        q = np.abs(local) - (self._half - self._radius)
        outside = np.hypot(*np.clip(q, 0.0, None).T)
        inside = np.minimum(q.max(axis=1), 0.0)
        result: FloatArray = outside + inside - self._radius
        return result

    def _local_contains(self, local: FloatArray) -> BoolArray:
        result: BoolArray = self._local_signed_distance(local) <= 0.0
        return result


class Palm(_RoundedBox):
    """A flat palm: a rounded rectangle.

    Args:
        centre: metres, world frame, shape (2,).
        angle: radians, from the world x axis to the local x (across-hand) axis.
        size: full (width across the hand, length along it), metres.
        corner_radius: metres, at most half the smaller side.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s.
    """

    def __init__(
        self,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        size: ArrayLike = (0.075, 0.085),
        corner_radius: float = 0.02,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        half = 0.5 * _checks.vector2(size, "size")
        super().__init__(half, corner_radius, centre, angle, linear_velocity, angular_velocity)

    @property
    def size(self) -> tuple[float, float]:
        """Full (width, length), metres."""
        return (float(2.0 * self._half[0]), float(2.0 * self._half[1]))

    @property
    def corner_radius(self) -> float:
        """metres."""
        return self._radius


class HandEdge(_RoundedBox):
    """The edge of a hand laid on the table: a stadium (a long, thin rectangle with
    semicircular ends).

    Args:
        centre, linear_velocity, angular_velocity: as for :class:`Palm`.
        angle: radians, from the world x axis to the local x (across-edge) axis; the
            length runs along local y.
        length: end to end, metres.
        width: metres, less than or equal to ``length``.
    """

    def __init__(
        self,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        length: float = 0.09,
        width: float = 0.02,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        long = _checks.positive(length, "length")
        wide = _checks.positive(width, "width")
        if wide > long:
            raise ValueError(f"width ({width!r} m) must not exceed length ({length!r} m)")
        super().__init__(
            (0.5 * wide, 0.5 * long), 0.5 * wide, centre, angle, linear_velocity, angular_velocity
        )

    @property
    def length(self) -> float:
        """End to end, metres."""
        return float(2.0 * self._half[1])

    @property
    def width(self) -> float:
        """metres."""
        return float(2.0 * self._half[0])
