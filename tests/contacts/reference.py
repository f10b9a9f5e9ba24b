"""The plain-numpy forms of the compiled per-frame kernels, as they stood before
the hot path was compiled (graspenv 0.1, issue 12): the oracles the kernels are
checked against on random inputs (tests/contacts/test_kernels.py). Not used by the
package, and using none of it: each function takes the arguments of the public
function it checks and gives its result, which that function's docstring describes;
the docstrings here say how the numpy form gets there."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

_CAP = 0.5
_SMOOTH_FROM = 8
_OVERLAP = 0.25
IntArray = NDArray[np.intp]


def _bounds(sizes: Sequence[int] | IntArray) -> IntArray:
    """Where each of several arrays laid end to end starts, then the total: (C + 1,)."""
    return np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)


def outlines_from_chains(
    chains: Sequence[NDArray[np.integer]],
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`graspenv.contacts.extract.outlines_from_chains`, bit for bit.

    Chains that never double back (fingertips, palms: the per-frame case) go through
    one fixed sequence of numpy calls together; a chain with a line or spur, or a
    single pixel, is capped on its own.
    """
    sizes = np.array([len(c) for c in chains], dtype=np.intp)
    bounds = _bounds(sizes)
    points = np.concatenate(chains).astype(np.float64)
    first, last = bounds[:-1], bounds[1:] - 1
    index = np.arange(len(points))
    after_index = index + 1
    after_index[last] = first
    before_index = index - 1
    before_index[first] = last
    before, after = points[before_index], points[after_index]
    tangent = after - before
    length = np.hypot(tangent[:, 0], tangent[:, 1])
    # OpenCV's outer borders have a negative shoelace area in (column, row), for
    # which (-dy, dx) of the tangent points out of the shape. Check rather than
    # trust it; a chain enclosing nothing has no inside, and either side will do.
    cross = points[:, 0] * after[:, 1] - points[:, 1] * after[:, 0]
    outward = np.where(np.add.reduceat(cross, first) <= 0.0, 1.0, -1.0)
    tip = length == 0.0  # the chain doubles back here: the end of a line or spur
    capped = np.add.reduceat(tip, first) > 0
    if capped.any():
        # The capped ones one by one, the others together again, in the chains' order.
        plain = np.flatnonzero(~capped).tolist()
        pieces: list[NDArray[np.float64]] = [np.zeros((0, 2))] * len(chains)
        if plain:
            together, cuts = outlines_from_chains([chains[i] for i in plain])
            for k, i in enumerate(plain):
                pieces[i] = together[cuts[k] : cuts[k + 1]]
        for i in np.flatnonzero(capped).tolist():
            pieces[i] = _capped_outline(points[bounds[i] : bounds[i + 1]], outward[i])
        return np.concatenate(pieces), _bounds([len(p) for p in pieces])
    side = np.repeat(outward, sizes)
    outline = _offset_outward(points, tangent, length, side)
    # The pixel staircase is 5 % longer than the edge it follows and spaces resampled
    # points unevenly. [1, 2, 1]/4 removes the zigzag but shrinks curves; following
    # it by [-1, 6, -1]/4 restores them to fourth order: together [-1, 4, 10, 4, -1]
    # / 16. Outlines of fewer than _SMOOTH_FROM points are left as they are.
    smoothed = np.repeat(sizes >= _SMOOTH_FROM, sizes)
    if not smoothed.any():
        return outline, bounds
    neighbours = outline[before_index] + outline[after_index]
    far = outline[before_index[before_index]] + outline[after_index[after_index]]
    smooth = (10.0 * outline + 4.0 * neighbours - far) / 16.0
    if smoothed.all():
        return smooth, bounds
    return np.where(smoothed[:, None], smooth, outline), bounds


def _offset_outward(
    points: NDArray[np.float64],
    tangent: NDArray[np.float64],
    length: NDArray[np.float64],
    side: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Points moved half a pixel along the dominant axis of their outward normal:
    0.5·max(|n_x|, |n_y|) along n, n = side · (-t_y, t_x) / |t| (lengths > 0)."""
    normal = np.empty_like(tangent)
    normal[:, 0] = -side * tangent[:, 1] / length
    normal[:, 1] = side * tangent[:, 0] / length
    offset = 0.5 * np.abs(normal).max(axis=1, keepdims=True)
    return points + offset * normal


def _capped_outline(points: NDArray[np.float64], outward: float) -> NDArray[np.float64]:
    """The outline of one chain that doubles back (or is a single pixel): offset as
    everywhere, with a square cap half a pixel beyond each end, then smoothed except
    at the caps' corners (so thin lines keep their footprint)."""
    if len(points) == 1:
        corners = np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, 1.0], [1.0, -1.0]])
        return points[0] + _CAP * corners
    ring = np.concatenate([points[-1:], points, points[:1]])
    before, after = ring[:-2], ring[2:]
    tangent = after - before
    length = np.hypot(tangent[:, 0], tangent[:, 1])
    tip = length == 0.0
    length[tip] = 1.0
    outline = _offset_outward(points, tangent, length, np.full(len(points), outward))
    pieces: list[NDArray[np.float64]] = []
    start = 0
    for end in np.flatnonzero(tip).tolist():
        arrive = points[end] - before[end]
        arrive /= np.hypot(arrive[0], arrive[1])
        side = outward * np.array([-arrive[1], arrive[0]])
        pieces.append(outline[start:end])
        # Two corners of a square cap, in the chain's order: first on the side the
        # chain arrives along, then on the side it leaves along.
        pieces.append(points[end] + _CAP * np.stack([arrive + side, arrive - side]))
        start = end + 1
    pieces.append(outline[start:])
    outline = np.concatenate(pieces)
    fixed = np.concatenate([np.full(len(piece), i % 2 == 1) for i, piece in enumerate(pieces)])
    if len(outline) < _SMOOTH_FROM:
        return outline
    ext = np.concatenate([outline[-2:], outline, outline[:2]])
    smooth = (10.0 * outline + 4.0 * (ext[1:-3] + ext[3:-1]) - (ext[:-4] + ext[4:])) / 16.0
    return np.where(fixed[:, None], outline, smooth)


def orient_ccw_batch(points: NDArray[np.float64], bounds: NDArray[np.intp]) -> NDArray[np.float64]:
    """:func:`graspenv.contacts.resample.orient_ccw_batch`, bit for bit: every
    polyline's shoelace sum in one ``np.add.reduceat``, then the clockwise ones
    reversed one by one."""
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


def resample_closed_batch(
    points: NDArray[np.float64],
    bounds: NDArray[np.intp],
    spacing: float,
    starts: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`graspenv.contacts.resample.resample_closed_batch` with ``starts`` given
    (a NaN row for none), up to rounding in the last bits: the arc lengths here run
    along all the polylines one after another, not along each from its own first
    vertex.

    Every polyline goes through the same fixed sequence of numpy calls, however many
    there are: the segment leaving each vertex, the point of each polyline closest to
    its start, then the targets placed along all of them at once.
    """
    if not (np.isfinite(spacing) and spacing > 0.0):
        raise ValueError(f"spacing must be finite and > 0, got {spacing}")
    total = len(points)
    sizes = np.diff(bounds)
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

    # A polyline with a start begins at its point closest to it (the earliest on a
    # tie): every vertex's segment projected onto its polyline's start at once. The
    # polylines without one have NaN distances, and no hits.
    origin = np.zeros(len(first))
    has = ~np.isnan(starts).any(axis=1)
    if has.any():
        start = np.repeat(starts, sizes, axis=0)
        squared = length * length
        along = np.einsum("ij,ij->i", start - points, step)
        t = np.clip(along / np.where(squared > 0.0, squared, 1.0), 0.0, 1.0)
        gap = points + t[:, None] * step - start
        distance = np.einsum("ij,ij->i", gap, gap)
        nearest = np.minimum.reduceat(distance, first)
        hits = np.flatnonzero(distance == np.repeat(nearest, sizes))
        best = hits[np.minimum(np.searchsorted(hits, first), hits.size - 1)][has]
        origin[has] = arc[best] + t[best] * length[best] - base[has]

    which = np.repeat(np.arange(len(count)), count)
    index = np.concatenate([np.arange(n) for n in count.tolist()])
    targets = np.mod(origin[which] + (perimeter / count)[which] * index, perimeter[which])
    targets += base[which]
    # side="right" skips zero-length segments (repeated vertices): a target sitting
    # exactly on a vertex is taken from the segment that leaves it.
    segment = np.minimum(np.searchsorted(arc, targets, side="right") - 1, last[which])
    edge = length[segment]
    fraction = (targets - arc[segment]) / np.where(edge > 0.0, edge, 1.0)
    return points[segment] + fraction[:, None] * step[segment], _bounds(count)


def anchors(has: NDArray[np.bool_], bounds: IntArray) -> IntArray:
    """:func:`new_point_anchors` of many contours at once (contour c is
    ``has[bounds[c]:bounds[c + 1]]``); indices along all of them."""
    anchor = np.full(len(has), -1, dtype=np.intp)
    kept = np.flatnonzero(has)
    lone = np.flatnonzero(~has)
    if kept.size == 0 or lone.size == 0:
        return anchor
    sizes = np.diff(bounds)
    owner = np.repeat(np.arange(len(sizes)), sizes)[lone]
    # Each contour's kept points are kept[low[c]:high[c]].
    low = np.searchsorted(kept, bounds[:-1])[owner]
    high = np.searchsorted(kept, bounds[1:])[owner]
    some = high > low  # a contour with no kept point leaves its lone points at -1
    if not some.all():
        lone, owner, low, high = lone[some], owner[some], low[some], high[some]
    after = np.searchsorted(kept, lone)  # first kept point above each lone point
    ahead = kept[np.where(after < high, after, low)]  # wrapping round the contour
    behind = kept[np.where(after > low, after - 1, high - 1)]
    size = sizes[owner]
    forward = (ahead - lone) % size
    backward = (lone - behind) % size
    anchor[lone] = np.where(backward <= forward, behind, ahead)
    return anchor


@dataclass(frozen=True)
class Blob:
    """A component of the current mask in world units, in raster order."""

    outline: NDArray[np.float64]
    centroid: NDArray[np.float64]


def match_rules(
    previous: Sequence[Any], blobs: Sequence[Blob], match_radius: float
) -> tuple[list[int | None], list[tuple[int, ...]]]:
    """Which previous id each blob keeps (None: new) and its sources."""
    keeps: list[int | None] = [None] * len(blobs)
    sources: list[tuple[int, ...]] = [()] * len(blobs)
    if not previous or not blobs:
        return keeps, sources
    prev_xy = np.array([c.centroid for c in previous])
    cur_xy = np.array([b.centroid for b in blobs])
    distance = np.linalg.norm(prev_xy[:, None, :] - cur_xy[None, :, :], axis=2)

    # 1. Motion: greedy one-to-one by distance, ties by previous id then raster.
    taken_prev = np.zeros(len(previous), dtype=bool)
    p_idx, c_idx = np.nonzero(distance <= match_radius)
    ids = np.array([c.id for c in previous])
    for n in np.lexsort((c_idx, ids[p_idx], distance[p_idx, c_idx])):
        p, c = int(p_idx[n]), int(c_idx[n])
        if taken_prev[p] or keeps[c] is not None:
            continue
        taken_prev[p] = True
        keeps[c] = previous[p].id

    def overlap(p: int, c: int) -> bool:
        return _overlap(previous[p].centroid, previous[p].outline, blobs[c])

    # 2. Merges: a leftover previous contact overlapping a current one.
    merged: dict[int, list[int]] = {c: [] for c in range(len(blobs))}
    joined: dict[int, list[int]] = {}
    for p in np.argsort(ids, kind="stable").tolist():
        if taken_prev[p]:
            continue
        near = [c for c in range(len(blobs)) if overlap(p, c)]
        if not near:
            continue
        c = min(near, key=lambda c: (distance[p, c], c))
        joined.setdefault(c, []).append(p)
        taken_prev[p] = True
    for c, ps in joined.items():
        if keeps[c] is None:
            nearest = min(ps, key=lambda p: (distance[p, c], previous[p].id))
            keeps[c] = previous[nearest].id
        merged[c].extend(previous[p].id for p in ps if previous[p].id != keeps[c])
    for c, kept in enumerate(keeps):
        if kept is not None:
            sources[c] = (kept, *sorted(merged[c]))

    # 3. Splits: a leftover current contact overlapping a previous one.
    for c in range(len(blobs)):
        if keeps[c] is not None:
            continue
        near = [p for p in range(len(previous)) if overlap(p, c)]
        if near:
            parent = min(near, key=lambda p: (distance[p, c], previous[p].id))
            sources[c] = (previous[parent].id,)
    return keeps, sources


def _overlap(centroid: NDArray[np.float64], outline: NDArray[np.float64], blob: Blob) -> bool:
    """Whether a previous contact (centroid (2,), outline (L, 2), metres, world frame)
    and a current blob overlap, in the sense of the module docstring."""
    reach = np.max(np.linalg.norm(outline - centroid, axis=1))
    blob_reach = np.max(np.linalg.norm(blob.outline - blob.centroid, axis=1))
    if np.linalg.norm(centroid - blob.centroid) > reach + blob_reach:
        return False
    if _inside(centroid[None, :], blob.outline)[0] or _inside(blob.centroid[None, :], outline)[0]:
        return True
    return bool(
        np.mean(_inside(outline, blob.outline)) >= _OVERLAP
        or np.mean(_inside(blob.outline, outline)) >= _OVERLAP
    )


def _inside(points: NDArray[np.float64], polygon: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Which points (K, 2) lie inside a closed polygon (L, 2), same frame; even-odd."""
    x, y = points[:, :1], points[:, 1:]
    xi, yi = polygon[None, :, 0], polygon[None, :, 1]
    xj, yj = np.roll(xi, -1, axis=1), np.roll(yi, -1, axis=1)
    straddles = (yi > y) != (yj > y)
    rise = np.where(straddles, yj - yi, 1.0)
    crossing = xi + (y - yi) * (xj - xi) / rise
    return np.count_nonzero(straddles & (x < crossing), axis=1) % 2 == 1


def clean_masks(
    masks: Sequence[NDArray[np.uint8]],
    vote_frames: int,
    close_px: int,
    fill_px: int,
    min_area: float,
) -> list[NDArray[np.uint8]]:
    """:class:`graspenv.contacts.cleanup.MaskCleaner` over a stream of masks, bit for
    bit: the form it had inside the tracker (2026-12-05), every step a whole-image
    numpy operation (the vote a sum of the last masks, each component's counts a
    ``bincount`` over the whole image)."""
    import math
    from collections import deque

    import cv2

    keeps = 0.5  # graspenv.contacts.cleanup.VOTE_KEEPS
    close = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (max(close_px, 1),) * 2)
    fill = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * fill_px + 1,) * 2)
    recent: deque[NDArray[np.uint8]] = deque(maxlen=vote_frames)
    last_seen: NDArray[np.uint8] | None = None

    def without_specks(touched: NDArray[np.uint8]) -> NDArray[np.uint8]:
        if min_area <= 1.0:
            return touched
        _, labels, stats, _ = cv2.connectedComponentsWithStats(touched, connectivity=8)
        kept = stats[:, cv2.CC_STAT_AREA] >= min_area
        kept[0] = False
        return np.asarray(kept[labels], np.uint8)

    def voted_mask(touched: NDArray[np.uint8]) -> NDArray[np.uint8]:
        recent.append(touched)
        if len(recent) == 1:
            return touched
        votes = np.sum(recent, axis=0, dtype=np.uint8)
        voted = votes > len(recent) // 2
        count, labels = cv2.connectedComponents(touched, connectivity=8)
        kept = np.bincount(labels[voted], minlength=count)
        area = np.bincount(labels.ravel(), minlength=count)
        moved = (kept < keeps * area) & (area >= min_area)
        moved[0] = False
        if not moved.any():
            return np.asarray(voted, np.uint8)
        as_seen = moved[labels]
        reach = 2 * round(2.0 * math.sqrt(float(area[moved].max()))) + 1
        trail = cv2.dilate(
            as_seen.astype(np.uint8), cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (reach, reach))
        )
        parts, where = cv2.connectedComponents(np.asarray(voted, np.uint8), connectivity=8)
        steady = np.zeros(parts, bool)
        steady[where[voted & (labels > 0) & ~as_seen]] = True
        left = np.zeros(parts, bool)
        left[where[voted & (trail != 0)]] = True
        left &= ~steady
        left[0] = False
        return np.asarray(voted & ~left[where] | as_seen, np.uint8)

    out = []
    for image in masks:
        clean = np.minimum(image, 1)
        if vote_frames > 1:
            clean = voted_mask(clean)
        if close_px > 1:
            clean = np.asarray(cv2.morphologyEx(clean, cv2.MORPH_CLOSE, close), np.uint8)
        if fill_px > 0:
            seen = clean
            if last_seen is not None:
                near = np.asarray(cv2.dilate(without_specks(clean), fill), np.uint8)
                clean = clean | (last_seen & near)
            last_seen = seen
        out.append(clean)
    return out
