"""Closed polylines: even arc-length resampling and one orientation everywhere.

All functions take plain (N, 2) arrays and work in whatever planar frame they are
given; the contact pipeline calls them in the world frame (metres, y up), where
counter-clockwise means counter-clockwise seen from above the table.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "bounds_of",
    "orient_ccw",
    "orient_ccw_batch",
    "owners_of",
    "resample_closed",
    "resample_closed_batch",
    "signed_area",
]


def bounds_of(sizes: Sequence[int] | NDArray[np.intp]) -> NDArray[np.intp]:
    """Where each of several arrays laid end to end starts, and the total.

    The batch functions here and in :mod:`graspenv.contacts.matching` take every
    contour of a frame as one array and these bounds: contour c is
    ``points[bounds[c]:bounds[c + 1]]``.

    Args:
        sizes: the arrays' lengths, (C,).

    Returns:
        Shape (C + 1,): 0, then the running totals.
    """
    bounds = np.zeros(len(sizes) + 1, dtype=np.intp)
    np.cumsum(sizes, out=bounds[1:])
    return bounds


def owners_of(bounds: NDArray[np.intp]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """For each element of arrays laid end to end (:func:`bounds_of`): which array it
    belongs to, and its index within that array; shapes (bounds[-1],)."""
    sizes = np.diff(bounds)
    owner = np.repeat(np.arange(len(sizes)), sizes)
    return owner, np.arange(bounds[-1]) - bounds[owner]


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


def orient_ccw_batch(points: NDArray[np.float64], bounds: NDArray[np.intp]) -> NDArray[np.float64]:
    """:func:`orient_ccw` for many closed polylines in one pass.

    Args:
        points: the polylines one after another, shape (T, 2), right-handed frame;
            polyline c is ``points[bounds[c]:bounds[c + 1]]``.
        bounds: shape (C + 1,), as in :func:`resample_closed_batch`.

    Returns:
        Shape (T, 2), same bounds: each polyline counter-clockwise (those already so
        are unchanged; the others reversed with their first vertex kept first). The
        input itself when every polyline already runs counter-clockwise.
    """
    first = bounds[:-1]
    # The shoelace about each polyline's first vertex (see _shoelace).
    rel = points - np.repeat(points[first], np.diff(bounds), axis=0)
    following = np.arange(1, len(points) + 1)
    following[bounds[1:] - 1] = first
    cross = rel[:, 0] * rel[following, 1] - rel[:, 1] * rel[following, 0]
    clockwise = np.flatnonzero(np.add.reduceat(cross, first) < 0.0)
    if clockwise.size == 0:
        return points
    oriented = points.copy()
    for c in clockwise.tolist():
        lo, hi = bounds[c], bounds[c + 1]
        oriented[lo + 1 : hi] = points[lo + 1 : hi][::-1]
    return oriented


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
    starts = None
    if start is not None:
        target = np.asarray(start, dtype=np.float64)
        if target.shape != (2,) or not np.isfinite(target).all():
            raise ValueError(f"start must be a finite point of shape (2,), got {target.shape}")
        starts = target[None, :]
    resampled, _ = resample_closed_batch(points, np.array([0, len(points)]), spacing, starts)
    return resampled


def resample_closed_batch(
    points: NDArray[np.float64],
    bounds: NDArray[np.intp],
    spacing: float,
    starts: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`resample_closed` for many closed polylines in one pass.

    The per-frame path: every contact of a frame is resampled by the same fixed
    sequence of numpy calls, however many there are. Polyline c gives exactly what
    ``resample_closed(points[bounds[c]:bounds[c + 1]], spacing, starts[c])`` gives, up
    to rounding in the last bits (its arc lengths are measured along all of them).

    Args:
        points: the polylines' vertices one after another, shape (T, 2), each closed,
            same frame (metres, world frame for contacts), all finite.
        bounds: polyline c is ``points[bounds[c]:bounds[c + 1]]``, shape (C + 1,),
            ``bounds[0] == 0``, strictly increasing, ``bounds[-1] == T``.
        spacing: requested arc length between consecutive points.
        starts: start point of each polyline, shape (C, 2), a row with a NaN for
            none (start at the first vertex); ``None`` for none at all.

    Returns:
        (resampled, resampled_bounds): the resampled points one polyline after
        another, shape (R, 2), and their bounds, shape (C + 1,).

    Raises:
        ValueError: a non-positive spacing or a polyline of zero perimeter.
    """
    if not (np.isfinite(spacing) and spacing > 0.0):
        raise ValueError(f"spacing must be finite and > 0, got {spacing}")
    total = len(points)
    first, last = bounds[:-1], bounds[1:] - 1
    following = np.arange(1, total + 1)
    following[last] = first
    step = points[following] - points
    length = np.hypot(step[:, 0], step[:, 1])
    cumulative = np.cumsum(length)
    # Where each vertex lies along all the polylines, one after another.
    arc = np.empty(total)
    arc[0] = 0.0
    arc[1:] = cumulative[:-1]
    base = arc[first]
    perimeter = cumulative[last] - base
    if not (perimeter > 0.0).all():
        raise ValueError("polyline has zero perimeter; it needs at least two distinct points")
    count = np.maximum(np.rint(perimeter / spacing).astype(np.intp), 3)

    origin = np.zeros(len(first))
    if starts is not None:
        has = ~np.isnan(starts).any(axis=1)
        if has.any():
            origin[has] = (
                _closest_arc_positions(points, bounds, step, length, arc, starts)[has] - base[has]
            )

    resampled_bounds = bounds_of(count)
    which, index = owners_of(resampled_bounds)
    targets = np.mod(origin[which] + (perimeter / count)[which] * index, perimeter[which])
    targets += base[which]
    # side="right" skips zero-length segments (repeated vertices): a target sitting
    # exactly on a vertex is taken from the segment that leaves it.
    segment = np.minimum(np.searchsorted(arc, targets, side="right") - 1, last[which])
    edge = length[segment]
    fraction = (targets - arc[segment]) / np.where(edge > 0.0, edge, 1.0)
    return points[segment] + fraction[:, None] * step[segment], resampled_bounds


def _closest_arc_positions(
    points: NDArray[np.float64],
    bounds: NDArray[np.intp],
    step: NDArray[np.float64],
    length: NDArray[np.float64],
    arc: NDArray[np.float64],
    starts: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Arc position (along all polylines) of each polyline's point closest to its
    start (the earliest on a tie), shape (C,); NaN where the start is NaN."""
    sizes = np.diff(bounds)
    start = np.repeat(starts, sizes, axis=0)
    squared = length * length
    along = np.einsum("ij,ij->i", start - points, step)
    t = np.clip(along / np.where(squared > 0.0, squared, 1.0), 0.0, 1.0)
    gap = points + t[:, None] * step - start
    distance = np.einsum("ij,ij->i", gap, gap)
    nearest = np.minimum.reduceat(distance, bounds[:-1])
    hits = np.flatnonzero(distance == np.repeat(nearest, sizes))
    if hits.size == 0:
        return np.full(len(sizes), np.nan)
    best = hits[np.minimum(np.searchsorted(hits, bounds[:-1]), hits.size - 1)]
    position = arc[best] + t[best] * length[best]
    position[np.isnan(nearest)] = np.nan
    return position
