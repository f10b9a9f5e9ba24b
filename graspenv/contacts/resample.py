"""Closed polylines: even arc-length resampling and one orientation everywhere.

All functions take plain (N, 2) arrays and work in whatever planar frame they are
given; the contact pipeline calls them in the world frame (metres, y up), where
counter-clockwise means counter-clockwise seen from above the table.
"""

from __future__ import annotations

from typing import NamedTuple, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.geometry import Polylines, shoelace
from graspenv.jit import njit

G = TypeVar("G", bound=np.generic)

__all__ = [
    "checked_bounds",
    "gather",
    "gather_rows",
    "orient_ccw",
    "orient_ccw_batch",
    "owners_of",
    "resample_closed",
    "resample_closed_batch",
    "signed_area",
]


def owners_of(bounds: NDArray[np.intp]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """For each element of arrays laid end to end
    (:func:`~graspenv.geometry.bounds_of`): which array it belongs to, and its index
    within that array; shapes (bounds[-1],)."""
    sizes = np.diff(bounds)
    owner = np.repeat(np.arange(len(sizes)), sizes)
    return owner, np.arange(bounds[-1]) - bounds[owner]


def checked_bounds(bounds: ArrayLike, total: int, name: str = "bounds") -> NDArray[np.intp]:
    """``bounds`` of arrays laid end to end over ``total`` rows
    (:class:`~graspenv.geometry.Polylines`) as an intp array, or a ValueError: the
    compiled kernels do not check indices, so every public batch function checks its
    bounds here first."""
    array = np.asarray(bounds)
    if array.ndim != 1 or len(array) < 1 or not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"{name} must be a 1-D integer array, got {array!r}")
    if array[0] != 0 or array[-1] != total or np.any(np.diff(array) <= 0):
        raise ValueError(
            f"{name} must rise strictly from 0 to {total} (the number of points), got "
            f"{array.tolist()}"
        )
    return array.astype(np.intp, copy=False)


@njit
def gather(
    points: NDArray[G], bounds: NDArray[np.intp], order: NDArray[np.intp]
) -> tuple[NDArray[G], NDArray[np.intp]]:
    """Some of several arrays laid end to end (:class:`~graspenv.geometry.Polylines`),
    in a new order.

    Compiled for any dtype and row shape (one machine code per combination), for the
    per-frame stages: its indices are not checked (see :func:`checked_bounds`).

    Args:
        points: the arrays one after another, shape (T, ...).
        bounds: array c is ``points[bounds[c]:bounds[c + 1]]``, shape (C + 1,).
        order: which arrays to take, in order, shape (K,).

    Returns:
        (gathered, gathered_bounds): ``points[bounds[order[k]]:bounds[order[k] + 1]]``
        for k = 0, 1, ... one after another, and their bounds, shape (K + 1,).
    """
    rows, new_bounds = gather_rows(bounds, order)
    return points[rows], new_bounds


@njit
def gather_rows(
    bounds: NDArray[np.intp], order: NDArray[np.intp]
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The rows :func:`gather` takes, and their bounds: for arrays laid end to end
    that travel together (one bounds for several), index each with the same rows.

    Args:
        bounds: array c is ``points[bounds[c]:bounds[c + 1]]``, shape (C + 1,).
        order: which arrays to take, in order, shape (K,).

    Returns:
        (rows, gathered_bounds): ``bounds[order[k]]``, ..., ``bounds[order[k] + 1] - 1``
        for k = 0, 1, ... one after another, and their bounds, shape (K + 1,).
    """
    new_bounds = np.zeros(len(order) + 1, np.intp)
    for k in range(len(order)):
        new_bounds[k + 1] = new_bounds[k] + bounds[order[k] + 1] - bounds[order[k]]
    rows = np.empty(new_bounds[-1], np.intp)
    for k in range(len(order)):
        lo = bounds[order[k]]
        for i in range(new_bounds[k + 1] - new_bounds[k]):
            rows[new_bounds[k] + i] = lo + i
    return rows, new_bounds


def _as_polyline(polyline: ArrayLike, name: str = "polyline") -> NDArray[np.float64]:
    points = np.asarray(polyline, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
        raise ValueError(f"{name} must have shape (N, 2) with N >= 1, got {points.shape}")
    if not np.isfinite(points).all():
        raise ValueError(f"{name} must be finite")
    return points


def signed_area(polyline: ArrayLike) -> float:
    """Signed area enclosed by a closed polyline (shoelace formula).

    Args:
        polyline: vertices, shape (N, 2), closed (the last vertex joins the first),
            in a right-handed planar frame (metres, world frame, for contacts).

    Returns:
        Area in the frame's units squared; positive when the vertices run
        counter-clockwise in that frame, zero for fewer than three vertices or a line.
    """
    return shoelace(_as_polyline(polyline))


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
    if shoelace(points) >= 0.0:
        return points
    return np.concatenate([points[:1], points[:0:-1]])


def orient_ccw_batch(points: NDArray[np.float64], bounds: NDArray[np.intp]) -> NDArray[np.float64]:
    """:func:`orient_ccw` for many closed polylines in one compiled pass.

    Args:
        points: the polylines one after another, shape (T, 2), right-handed frame;
            polyline c is ``points[bounds[c]:bounds[c + 1]]``.
        bounds: shape (C + 1,), as in :func:`resample_closed_batch`.

    Returns:
        Shape (T, 2), same bounds: each polyline counter-clockwise (those already so
        are unchanged; the others reversed with their first vertex kept first). The
        input itself when every polyline already runs counter-clockwise.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2:
        raise ValueError(f"points must have shape (T, 2), got {points.shape}")
    bounds = checked_bounds(bounds, len(points))
    oriented, changed = orient_ccw_kernel(np.ascontiguousarray(points), bounds)
    return oriented if changed else points


@njit
def orient_ccw_kernel(
    points: NDArray[np.float64], bounds: NDArray[np.intp]
) -> tuple[NDArray[np.float64], bool]:
    """:func:`orient_ccw_batch`, and whether any polyline was reversed."""
    oriented = points
    changed = False
    for c in range(len(bounds) - 1):
        lo, hi = bounds[c], bounds[c + 1]
        # The shoelace about the first vertex (see graspenv.geometry.shoelace).
        x0, y0 = points[lo, 0], points[lo, 1]
        cross = 0.0
        for i in range(lo + 1, hi - 1):
            cross += (points[i, 0] - x0) * (points[i + 1, 1] - y0) - (points[i, 1] - y0) * (
                points[i + 1, 0] - x0
            )
        if cross >= 0.0:
            continue
        if not changed:
            oriented = points.copy()
            changed = True
        for k in range(1, hi - lo):
            oriented[lo + k, 0] = points[hi - k, 0]
            oriented[lo + k, 1] = points[hi - k, 1]
    return oriented, changed


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
) -> Polylines:
    """:func:`resample_closed` for many closed polylines in one pass.

    The per-frame path: every contact of a frame is resampled in one compiled call,
    however many there are; polyline c gives exactly what
    ``resample_closed(points[bounds[c]:bounds[c + 1]], spacing, starts[c])`` gives
    (arc lengths are measured along each polyline from its own first vertex).

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
        ValueError: malformed points, bounds or starts, a non-positive spacing or a
            polyline of zero perimeter.
    """
    if not (np.isfinite(spacing) and spacing > 0.0):
        raise ValueError(f"spacing must be finite and > 0, got {spacing}")
    points = np.ascontiguousarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or not np.isfinite(points).all():
        raise ValueError(f"points must be finite with shape (T, 2), got {points.shape}")
    bounds = checked_bounds(bounds, len(points))
    if starts is None:
        starts = np.full((len(bounds) - 1, 2), np.nan)
    starts = np.ascontiguousarray(starts, dtype=np.float64)
    if starts.shape != (len(bounds) - 1, 2):
        raise ValueError(
            f"starts must have shape ({len(bounds) - 1}, 2), one row a polyline, got {starts.shape}"
        )
    return resample_kernel(Polylines(points, bounds), float(spacing), starts)


class _Edges(NamedTuple):
    """The edge leaving each vertex of closed polylines laid end to end, the last
    vertex's running back to the polyline's first (compiled code only).

    Attributes:
        points: the vertices, where each edge starts, shape (T, 2).
        step: each edge's vector, shape (T, 2).
        length: each edge's length, shape (T,).
        arc: where each vertex lies along its own polyline, shape (T,).
    """

    points: NDArray[np.float64]
    step: NDArray[np.float64]
    length: NDArray[np.float64]
    arc: NDArray[np.float64]


@njit
def _edges(polylines: Polylines) -> tuple[_Edges, NDArray[np.float64]]:
    """Each polyline's edges and its perimeter; raises ValueError for a polyline of
    zero perimeter."""
    points, bounds = polylines
    count = len(bounds) - 1
    total = len(points)
    step = np.empty((total, 2))
    length = np.empty(total)
    arc = np.empty(total)
    perimeter = np.empty(count)
    for c in range(count):
        lo, hi = bounds[c], bounds[c + 1]
        along = 0.0
        for i in range(lo, hi):
            j = i + 1 if i + 1 < hi else lo
            step[i, 0] = points[j, 0] - points[i, 0]
            step[i, 1] = points[j, 1] - points[i, 1]
            length[i] = np.hypot(step[i, 0], step[i, 1])
            arc[i] = along
            along += length[i]
        perimeter[c] = along
        if not along > 0.0:
            raise ValueError("polyline has zero perimeter; it needs at least two distinct points")
    return _Edges(points, step, length, arc), perimeter


@njit
def _point_at(edges: _Edges, lo: int, hi: int, target: float, out: NDArray[np.float64]) -> None:
    """The point at arc position ``target`` (within one perimeter) of polyline
    ``lo:hi``, written to ``out`` (2,)."""
    points, step, length, arc = edges
    # side="right" skips zero-length segments (repeated vertices): a target sitting
    # exactly on a vertex is taken from the segment that leaves it.
    found = int(np.searchsorted(arc[lo:hi], target, side="right"))
    segment = lo + min(found - 1, hi - lo - 1)
    edge = length[segment]
    fraction = (target - arc[segment]) / (edge if edge > 0.0 else 1.0)
    out[0] = points[segment, 0] + fraction * step[segment, 0]
    out[1] = points[segment, 1] + fraction * step[segment, 1]


@njit
def resample_kernel(polylines: Polylines, spacing: float, starts: NDArray[np.float64]) -> Polylines:
    """:func:`resample_closed_batch` once its arguments are checked; raises its
    ValueError for a polyline of zero perimeter (in the per-frame stages that cannot
    happen: every contact outline encloses an area)."""
    bounds = polylines.bounds
    count = len(bounds) - 1
    edges, perimeter = _edges(polylines)
    sizes = np.empty(count, np.intp)
    for c in range(count):
        sizes[c] = max(int(np.rint(perimeter[c] / spacing)), 3)
    out_bounds = np.zeros(count + 1, np.intp)
    out_bounds[1:] = np.cumsum(sizes)
    out = np.empty((out_bounds[-1], 2))
    for c in range(count):
        lo, hi = bounds[c], bounds[c + 1]
        origin = 0.0
        if not (np.isnan(starts[c, 0]) or np.isnan(starts[c, 1])):
            origin = _closest_arc_position(edges, lo, hi, starts[c])
        gap = perimeter[c] / sizes[c]
        for k in range(sizes[c]):
            _point_at(edges, lo, hi, (origin + gap * k) % perimeter[c], out[out_bounds[c] + k])
    return Polylines(out, out_bounds)


@njit
def follow_kernel(polylines: Polylines, spacing: float, predicted: Polylines) -> Polylines:
    """Points on each closed polyline where its ``predicted`` points land, not evenly
    re-spaced (compiled, for the per-frame stage; nothing is checked).

    Every predicted point (last frame's points carried by their contact's motion)
    moves onto the polyline along the predicted contour's normal there (the nearest
    crossing within a ``spacing``; where there is none, the polyline's nearest
    point), so the points move as the contact moved and do not slide along its
    outline: an uneven outline moves them in and out, not along. Resampling evenly
    instead moves point k by k times the change of the perimeter over the point
    count, and a pixelated outline's perimeter changes every frame. A landing within
    half a ``spacing`` of the last one kept is dropped; a gap of more than one and a
    half spacings is filled with evenly spaced points. Where the landings do not run
    once round the polyline in order (a contact whose shape changed under them), or
    fewer than three are left, the polyline is resampled evenly from the first
    landing (as :func:`resample_kernel` from that start).

    Args:
        polylines: the new outlines, closed, metres.
        spacing: the contour spacing, metres.
        predicted: each outline's predicted points, in order round it (counter-
            clockwise, as the outlines), at least one an outline.

    Returns:
        The points, one set per polyline, in the order of the landings, the first
        landing's first.
    """
    bounds = polylines.bounds
    count = len(bounds) - 1
    edges, perimeter = _edges(polylines)
    pred_points, pred_bounds = predicted
    # At most: every landing kept, and each gap filled at the spacing.
    most = 0
    for c in range(count):
        most += (pred_bounds[c + 1] - pred_bounds[c]) + int(perimeter[c] / spacing) + 3
    out = np.empty((most, 2))
    out_bounds = np.zeros(count + 1, np.intp)
    n = 0
    for c in range(count):
        lo, hi = bounds[c], bounds[c + 1]
        p_lo, p_hi = pred_bounds[c], pred_bounds[c + 1]
        length = perimeter[c]
        count_k = p_hi - p_lo
        landed = np.empty(count_k)
        for k in range(count_k):
            point = pred_points[p_lo + k]
            # Along the predicted contour's normal at the point (the chord of its two
            # neighbours turned a right angle), so that an uneven outline moves the
            # point in and out, not along; the nearest point where that line misses.
            after = pred_points[p_lo + (k + 1) % count_k]
            before = pred_points[p_lo + (k - 1) % count_k]
            landed[k] = _normal_arc_position(
                edges, lo, hi, point, after[1] - before[1], before[0] - after[0], spacing
            )
            if np.isnan(landed[k]):
                landed[k] = _closest_arc_position(edges, lo, hi, point)
        # Once round in order: the forward steps between landings add up to one turn.
        turn = 0.0
        for k in range(len(landed)):
            turn += (landed[(k + 1) % len(landed)] - landed[k]) % length
        kept = np.empty(len(landed))
        m = 0
        if len(landed) >= 3 and turn < 1.5 * length:
            for k in range(len(landed)):
                if m == 0 or (landed[k] - kept[m - 1]) % length >= 0.5 * spacing:
                    kept[m] = landed[k]
                    m += 1
            if m > 1 and (kept[0] - kept[m - 1]) % length < 0.5 * spacing:
                m -= 1
        if m < 3:
            size = max(int(np.rint(length / spacing)), 3)
            gap = length / size
            origin = landed[0] if len(landed) else 0.0
            for k in range(size):
                _point_at(edges, lo, hi, (origin + gap * k) % length, out[n])
                n += 1
            out_bounds[c + 1] = n
            continue
        for k in range(m):
            _point_at(edges, lo, hi, kept[k], out[n])
            n += 1
            step = (kept[(k + 1) % m] - kept[k]) % length
            if step > 1.5 * spacing:
                extra = int(np.rint(step / spacing)) - 1
                for e in range(1, extra + 1):
                    _point_at(edges, lo, hi, (kept[k] + step * e / (extra + 1)) % length, out[n])
                    n += 1
        out_bounds[c + 1] = n
    return Polylines(out[:n].copy(), out_bounds)


@njit
def _normal_arc_position(
    edges: _Edges,
    lo: int,
    hi: int,
    point: NDArray[np.float64],
    nx: float,
    ny: float,
    reach: float,
) -> float:
    """Arc position along the polyline of edges ``lo:hi`` where the line through
    ``point`` along (``nx``, ``ny``) meets it nearest ``point``, within ``reach``;
    NaN where it meets none."""
    points, step, length, arc = edges
    norm = np.hypot(nx, ny)
    if not norm > 0.0:
        return np.nan
    nx, ny = nx / norm, ny / norm
    best = np.nan
    best_s = reach
    for i in range(lo, hi):
        dx, dy = step[i, 0], step[i, 1]
        denominator = dx * ny - dy * nx
        if abs(denominator) < 1e-12 * (length[i] + 1e-30):
            continue
        wx, wy = point[0] - points[i, 0], point[1] - points[i, 1]
        u = (wx * ny - wy * nx) / denominator
        if u < 0.0 or u > 1.0:
            continue
        along = (wx * dy - wy * dx) / denominator
        if abs(along) <= best_s:
            best_s = abs(along)
            best = arc[i] + u * length[i]
    return best


@njit
def _closest_arc_position(edges: _Edges, lo: int, hi: int, start: NDArray[np.float64]) -> float:
    """Arc position along the polyline of edges ``lo:hi`` of its point closest to
    ``start`` (the earliest on a tie)."""
    points, step, length, arc = edges
    best = -1
    best_distance = np.inf
    best_t = 0.0
    for i in range(lo, hi):
        squared = length[i] * length[i]
        along = (start[0] - points[i, 0]) * step[i, 0] + (start[1] - points[i, 1]) * step[i, 1]
        t = min(max(along / (squared if squared > 0.0 else 1.0), 0.0), 1.0)
        gx = points[i, 0] + t * step[i, 0] - start[0]
        gy = points[i, 1] + t * step[i, 1] - start[1]
        distance = gx * gx + gy * gy
        if distance < best_distance:
            best, best_distance, best_t = i, distance, t
    return arc[best] + best_t * length[best]
