"""Closed polylines: even arc-length resampling and one orientation everywhere.

All functions take plain (N, 2) arrays and work in whatever planar frame they are
given; the contact pipeline calls them in the world frame (metres, y up), where
counter-clockwise means counter-clockwise seen from above the table.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["orient_ccw", "resample_closed", "signed_area"]


def _as_polyline(polyline: ArrayLike, name: str = "polyline") -> NDArray[np.float64]:
    points = np.asarray(polyline, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
        raise ValueError(f"{name} must have shape (N, 2) with N >= 1, got {points.shape}")
    if not np.isfinite(points).all():
        raise ValueError(f"{name} must be finite")
    return points


def _shoelace(points: NDArray[np.float64]) -> float:
    # About the first vertex, so world coordinates far from the origin lose no
    # precision to the cancelling cross products.
    rel = points[1:] - points[0]
    return 0.5 * float(np.sum(rel[:-1, 0] * rel[1:, 1] - rel[:-1, 1] * rel[1:, 0]))


def signed_area(polyline: ArrayLike) -> float:
    """Signed area enclosed by a closed polyline (shoelace formula).

    Args:
        polyline: vertices, shape (N, 2), closed (the last vertex joins the first),
            in a right-handed planar frame (metres, world frame, for contacts).

    Returns:
        Area in the frame's units squared; positive when the vertices run
        counter-clockwise in that frame, zero for fewer than three vertices or a line.
    """
    return _shoelace(_as_polyline(polyline))


def orient_ccw(polyline: ArrayLike) -> NDArray[np.float64]:
    """The same closed polyline running counter-clockwise.

    Args:
        polyline: vertices, shape (N, 2), closed, right-handed frame (metres, world
            frame, y up, for contacts: counter-clockwise seen from above the table).
            Image coordinates (column, row) are left-handed: pass world points.

    Returns:
        Shape (N, 2), float64: the input when its signed area is >= 0, otherwise its
        vertices in reverse order with the first vertex kept first (so a start point
        chosen before orienting stays the start).
    """
    points = _as_polyline(polyline)
    if _shoelace(points) >= 0.0:
        return points
    return np.concatenate([points[:1], points[:0:-1]])


def resample_closed(
    polyline: ArrayLike, spacing: float, start: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Resample a closed polyline to points evenly spaced in arc length.

    M = max(3, round(perimeter / spacing)) points are placed exactly perimeter / M
    apart along the polyline (so the realised spacing is within ±10 % of ``spacing``
    whenever the perimeter is at least five spacings), keeping the polyline's
    orientation.

    Args:
        polyline: vertices, shape (N, 2), closed (the last vertex joins the first;
            repeating the first vertex at the end is harmless), metres, world frame
            for contacts.
        spacing: requested arc length between consecutive points, same unit.
        start: a point, shape (2,), same frame; the first resampled point is the point
            of the polyline closest to it (the earliest along the polyline on a tie).
            ``None`` starts at the first vertex.

    Returns:
        Shape (M, 2), M ≥ 3, float64, same frame and orientation.

    Raises:
        ValueError: a malformed polyline, a non-positive spacing, or a polyline of
            zero perimeter (a single point has no footprint to sample: outline a pixel
            as its square, as :func:`graspenv.contacts.extract.outline_from_chain` does).
    """
    points = _as_polyline(polyline)
    if not (np.isfinite(spacing) and spacing > 0.0):
        raise ValueError(f"spacing must be finite and > 0, got {spacing}")
    step = np.concatenate([points[1:], points[:1]]) - points
    length = np.hypot(step[:, 0], step[:, 1])
    arc = np.concatenate([[0.0], np.cumsum(length)])
    perimeter = float(arc[-1])
    if perimeter <= 0.0:
        raise ValueError("polyline has zero perimeter; it needs at least two distinct points")

    count = max(3, round(perimeter / spacing))
    origin = 0.0
    if start is not None:
        origin = _closest_arc_position(points, step, length, arc, start)
    targets = np.mod(origin + (perimeter / count) * np.arange(count), perimeter)
    # side="right" skips zero-length segments (repeated vertices): a target sitting
    # exactly on a vertex is taken from the segment that leaves it.
    segment = np.minimum(np.searchsorted(arc, targets, side="right") - 1, len(points) - 1)
    safe = np.where(length[segment] > 0.0, length[segment], 1.0)
    fraction = (targets - arc[segment]) / safe
    return points[segment] + fraction[:, None] * step[segment]


def _closest_arc_position(
    points: NDArray[np.float64],
    step: NDArray[np.float64],
    length: NDArray[np.float64],
    arc: NDArray[np.float64],
    start: ArrayLike,
) -> float:
    """Arc-length position of the polyline point closest to ``start``."""
    target = np.asarray(start, dtype=np.float64)
    if target.shape != (2,) or not np.isfinite(target).all():
        raise ValueError(f"start must be a finite point of shape (2,), got {target.shape}")
    squared = length * length
    along = np.einsum("ij,ij->i", target - points, step)
    t = np.clip(along / np.where(squared > 0.0, squared, 1.0), 0.0, 1.0)
    gap = points + t[:, None] * step - target
    best = int(np.argmin(np.einsum("ij,ij->i", gap, gap)))
    return float(arc[best] + t[best] * length[best])
