"""Contacts tracked from one camera frame to the next.

:class:`ContactTracker` turns each contact mask into a :class:`ContactFrame`: the
components of the mask (:mod:`graspenv.contacts.extract`) as world-frame outlines,
resampled contours, centroids and areas, each with an id that persists while the
finger stays down.

**Matching rule**, applied in this order every frame:

1. *Motion.* Every (previous, current) pair whose centroids are at most
   ``ContactConfig.match_radius`` apart is a candidate; candidates are taken greedily
   in order of distance (ties: lower previous id, then lower current index in raster
   order) and each contact is taken at most once. A current contact taken this way
   continues its previous one: same id, status ``"continuing"``.
2. *Merges.* A previous contact left over that *overlaps* a current contact has
   merged into the nearest current contact it overlaps (centroid distance, ties to
   the lower index). If that current contact already continues someone, the leftover
   is listed in its ``sources`` and removed. Otherwise it keeps the id of the nearest
   previous contact that merged into it (``"continuing"``; ties to the lower id),
   lists the others in ``sources``, and they are removed. A palm coming down over two
   fingertips, its centroid far from both, continues the nearer one.
3. *Splits.* A current contact left over that overlaps a previous contact has split
   off the nearest previous contact it overlaps: ``"new"``, a fresh id, and
   ``sources == (parent id,)``. (The parent itself was settled in step 1 or 2:
   overlap is symmetric, so a parent still left over after step 1 went to the
   nearest piece it overlaps in step 2, which keeps its id.)
4. What is still left over is a touch-down (``"new"``, fresh id, no sources) or a
   lift-off (its id is in ``ContactFrame.removed``).

A previous contact and a current one *overlap* when either's centroid lies inside the
other's outline, or at least a quarter of either's outline lies inside the other's:
the second clause catches two fingertips that slide together faster than their own
half-width in one frame, whose old centroids the merged blob no longer covers. The
price: a finger lifted in the same frame as a neighbour slides over a quarter of its
old outline is reported as merged into the neighbour rather than lifted.

So ``sources`` is ``(id,)`` for a plain continuing contact, ``(id, *merged ids)``
(merged ids ascending) for one that swallowed others, ``(parent,)`` for a piece split
off a parent, and ``()`` for a touch-down. Fresh ids come from a counter that only
grows until :meth:`ContactTracker.reset`; new contacts of one frame get them in raster
order of their first pixel.

**Cost.** Candidates for every rule come from a sweep over the contacts sorted by x
(centroids within the match radius for rule 1; discs around the centroids that reach
every outline point, for the overlap of rules 2 and 3), so a frame costs about linear
time in its contacts rather than one test per pair; the rules then run in one
compiled call. A frame holds its contacts as arrays; the :class:`Contact` objects
are built only when asked for.

A continuing contact's contour starts at the point of its outline closest to its
previous contour's first point moved by the centroid's displacement, so index 0 does
not jump around the contour from frame to frame; a new contact's contour starts at
its outline's first point (near its top-left pixel). Contacts in a frame are listed in
ascending id.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Literal, NamedTuple, TypeVar

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.config import ContactConfig
from graspenv.contacts.cleanup import MaskCleaner
from graspenv.contacts.extract import components, traced_chains, validate_mask
from graspenv.contacts.resample import gather, orient_ccw_kernel, resample_kernel
from graspenv.geometry import Polylines, reach_from
from graspenv.jit import njit
from graspenv.surface.geometry import Surface

__all__ = ["Contact", "ContactFrame", "ContactSet", "ContactStatus", "ContactTracker"]

ContactStatus = Literal["new", "continuing"]
G = TypeVar("G", bound=np.generic)


def _frozen(array: NDArray[G]) -> NDArray[G]:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Contact:
    """One contact (a connected component of the mask) in one frame.

    Attributes:
        id: stable while the contact is tracked (see the module docstring).
        contour: metres, world frame, shape (N, 2), N ≥ 3, counter-clockwise seen
            from above, resampled evenly at the tracker's spacing
            (``ContactConfig.spacing``, ``"auto"`` resolved); read-only.
        outline: the un-resampled boundary, metres, world frame, shape (L, 2),
            counter-clockwise, on the pixel footprint's edge rather than through the
            boundary pixels' centres, lightly smoothed
            (:mod:`graspenv.contacts.extract`); read-only. Resample it yourself, e.g.
            from a predicted start point, with
            :func:`graspenv.contacts.resample.resample_closed`.
        centroid: metres, world frame, shape (2,); read-only.
        area: pixels inside the outer boundary times the pixel's area, m².
        status: ``"new"`` (touch-down or split-off piece) or ``"continuing"``.
        sources: ids of the previous frame this contact came from (module docstring).
    """

    id: int
    contour: NDArray[np.float64]
    outline: NDArray[np.float64]
    centroid: NDArray[np.float64]
    area: float
    status: ContactStatus
    sources: tuple[int, ...]

    @property
    def is_new(self) -> bool:
        """Whether the contact appeared this frame."""
        return self.status == "new"


class ContactSet(NamedTuple):
    """A frame's contacts as arrays, contact i in ascending id (the compiled stages
    take them as one argument).

    Attributes:
        ids: contact ids, ascending, int64, shape (C,).
        is_new: whether each contact appeared this frame, shape (C,).
        centroids: metres, world frame, shape (C, 2).
        areas: m², shape (C,).
        outlines: the outlines, metres, world frame, one set per contact.
        contours: the resampled contours, one set per contact.
    """

    ids: NDArray[np.int64]
    is_new: NDArray[np.bool_]
    centroids: NDArray[np.float64]
    areas: NDArray[np.float64]
    outlines: Polylines
    contours: Polylines


# Read-only like every frame's arrays: the compiled stages would otherwise compile a
# second version of themselves for writable ones.
_NO_POINTS = Polylines(_frozen(np.zeros((0, 2))), _frozen(np.zeros(1, np.intp)))
_NO_CONTACTS = ContactSet(
    ids=_frozen(np.zeros(0, np.int64)),
    is_new=_frozen(np.zeros(0, bool)),
    centroids=_NO_POINTS.points,
    areas=_frozen(np.zeros(0)),
    outlines=_NO_POINTS,
    contours=_NO_POINTS,
)


@dataclass(frozen=True, eq=False)
class ContactFrame:
    """The contacts of one camera frame, as arrays (contact i in ascending id).

    The per-frame stages read the arrays; :attr:`contacts` builds one
    :class:`Contact` per contact on first use. Every array is read-only.

    Attributes:
        index: frames since the tracker was created or reset, from 0.
        contact_set: the contacts' ids, centroids, areas, outlines and contours.
        removed: ids present in the previous frame and gone now (lift-offs and
            contacts merged into another), ascending.
        origins: where each contact came from, as the rules found it: the previous
            id it keeps or split off, or -1, shape (C,); with ``merged_ids`` (the
            previous ids each merged into another contact without keeping their id)
            and ``merged_into`` (the index of that contact here) they give
            :attr:`sources`.
    """

    index: int
    contact_set: ContactSet
    removed: tuple[int, ...]
    origins: NDArray[np.int64]
    merged_ids: NDArray[np.int64]
    merged_into: NDArray[np.intp]
    _contacts: list[tuple[Contact, ...]] = field(default_factory=list, repr=False)

    @classmethod
    def empty(cls, index: int = 0, removed: tuple[int, ...] = ()) -> ContactFrame:
        """A frame without contacts."""
        none = _NO_CONTACTS.ids
        return cls(index, _NO_CONTACTS, removed, none, none, _frozen(np.zeros(0, np.intp)))

    @property
    def contact_ids(self) -> NDArray[np.int64]:
        """Contact ids, ascending, shape (C,) (:attr:`ids` as a tuple)."""
        return self.contact_set.ids

    @property
    def contours(self) -> NDArray[np.float64]:
        """Every resampled contour one after another, metres, world frame, (R, 2);
        contact i's is ``contours[contour_bounds[i]:contour_bounds[i + 1]]``."""
        return self.contact_set.contours.points

    @property
    def contour_bounds(self) -> NDArray[np.intp]:
        """Shape (C + 1,)."""
        return self.contact_set.contours.bounds

    @property
    def sources(self) -> tuple[tuple[int, ...], ...]:
        """Each contact's sources (module docstring), in contact order."""
        swallowed: dict[int, list[int]] = {}
        for into, merged_id in zip(
            self.merged_into.tolist(), self.merged_ids.tolist(), strict=True
        ):
            swallowed.setdefault(into, []).append(merged_id)
        return tuple(
            () if origin < 0 else (origin, *sorted(swallowed.get(i, ()))) if not new else (origin,)
            for i, (origin, new) in enumerate(
                zip(self.origins.tolist(), self.contact_set.is_new.tolist(), strict=True)
            )
        )

    @property
    def contacts(self) -> tuple[Contact, ...]:
        """The contacts present, in ascending id (built on first use)."""
        if not self._contacts:
            arrays, sources = self.contact_set, self.sources
            (outlines, ob), (contours, cb) = arrays.outlines, arrays.contours
            self._contacts.append(
                tuple(
                    Contact(
                        id=int(arrays.ids[i]),
                        contour=contours[cb[i] : cb[i + 1]],
                        outline=outlines[ob[i] : ob[i + 1]],
                        centroid=arrays.centroids[i],
                        area=float(arrays.areas[i]),
                        status="new" if arrays.is_new[i] else "continuing",
                        sources=sources[i],
                    )
                    for i in range(len(arrays.ids))
                )
            )
        return self._contacts[0]

    @property
    def ids(self) -> tuple[int, ...]:
        """Ids of the contacts present, ascending."""
        return tuple(self.contact_ids.tolist())

    @property
    def new(self) -> tuple[Contact, ...]:
        """Contacts that appeared this frame (touch-downs and split-off pieces)."""
        return tuple(c for c in self.contacts if c.status == "new")

    @property
    def continuing(self) -> tuple[Contact, ...]:
        """Contacts that kept their id from the previous frame."""
        return tuple(c for c in self.contacts if c.status == "continuing")

    def get(self, contact_id: int) -> Contact | None:
        """The contact with this id, or ``None``."""
        at = int(np.searchsorted(self.contact_ids, contact_id))
        if at < len(self.contact_ids) and self.contact_ids[at] == contact_id:
            return self.contacts[at]
        return None

    def __getitem__(self, contact_id: int) -> Contact:
        contact = self.get(contact_id)
        if contact is None:
            raise KeyError(f"no contact with id {contact_id} in frame {self.index}")
        return contact

    def __contains__(self, contact_id: object) -> bool:
        return isinstance(contact_id, int | np.integer) and self.get(int(contact_id)) is not None

    def __iter__(self) -> Iterator[Contact]:
        return iter(self.contacts)

    def __len__(self) -> int:
        return len(self.contact_ids)


class ContactTracker:
    """Turns a stream of contact masks into tracked contacts.

    Args:
        surface: the table; gives the mask shape and the pixel-to-world transform.
        config: spacing of the contours, matching radius and smallest component.
    """

    def __init__(self, surface: Surface, config: ContactConfig | None = None) -> None:
        self.surface = surface
        self.config = (config if config is not None else ContactConfig()).resolved()
        self._spacing = self.config.contour_spacing()
        self._pixel_area = float(np.prod(surface.pixel_size))
        self._min_area = float(self.config.min_area_pixels(self._pixel_area))
        self._cleaner = MaskCleaner(self.config, self._min_area)
        # Pixels to world (Surface.pixel_to_world): x = (c + 0.5)·sx − w/2,
        # y = h/2 − (r + 0.5)·sy.
        sx, sy = surface.pixel_size
        self._settings = _Settings(
            width=surface.shape[1],
            min_area=self._min_area,
            pixel_area=self._pixel_area,
            transform=np.array([sx, sy, surface.size[0], surface.size[1]], dtype=float),
            radius=self.config.match_radius,
            spacing=self._spacing,
            outline_passes=self.config.outline_smoothing,
        )
        self._previous = ContactFrame.empty()
        self._next_id = 0
        self._index = 0

    def reset(self) -> None:
        """Forget all contacts; ids and the frame index start again from 0."""
        self._previous = ContactFrame.empty()
        self._next_id = 0
        self._index = 0
        self._cleaner.reset()

    def update(self, mask: object) -> ContactFrame:
        """Track the contacts of the next camera frame.

        Args:
            mask: contact image, shape (H, W) = ``surface.shape``, dtype bool or
                uint8, non-zero = touched; pixel frame (row 0 at the top).

        Returns:
            The frame's contacts, with new, continuing and removed ids.

        Raises:
            ValueError: the mask is not an (H, W) bool or uint8 numpy array of the
                surface's shape.
        """
        image = validate_mask(mask, self.surface.shape)
        if self._cleaner.needed:
            image = self._cleaner(image)
        before = self._previous
        if cv2.countNonZero(image) == 0:  # a fifth of tracing an empty frame's borders
            return self._advance(ContactFrame.empty(self._index, before.ids))
        chains, chain_bounds = traced_chains(image)
        now, origins, merged_into, removed = _track_frame(
            chains, chain_bounds, before.contact_set, self._next_id, self._settings
        )
        self._next_id += int(np.count_nonzero(now.is_new))
        for array in (now.ids, now.is_new, now.centroids, now.areas, *now.outlines, *now.contours):
            array.setflags(write=False)
        frame = ContactFrame(
            index=self._index,
            contact_set=now,
            removed=tuple(before.contact_ids[removed].tolist()),
            origins=_frozen(origins),
            merged_ids=_frozen(before.contact_ids[merged_into >= 0]),
            merged_into=_frozen(merged_into[merged_into >= 0]),
        )
        return self._advance(frame)

    def _advance(self, frame: ContactFrame) -> ContactFrame:
        self._previous = frame
        self._index += 1
        return frame


class _Settings(NamedTuple):
    """The tracker's fixed settings, as its compiled frame reads them.

    Attributes:
        width: the mask's width, pixels (the raster order of components).
        min_area: the smallest component kept, pixels.
        pixel_area: a pixel's area, m².
        transform: pixels to world, ``(sx, sy, w, h)`` (:func:`_to_world`).
        radius: ``ContactConfig.match_radius``, metres.
        spacing: the contours' spacing, metres.
        outline_passes: ``ContactConfig.outline_smoothing``.
    """

    width: int
    min_area: float
    pixel_area: float
    transform: NDArray[np.float64]
    radius: float
    spacing: float
    outline_passes: int


@njit
def _track_frame(
    chains: NDArray[np.int32],
    chain_bounds: NDArray[np.intp],
    before: ContactSet,
    next_id: int,
    settings: _Settings,
) -> tuple[ContactSet, NDArray[np.int64], NDArray[np.intp], NDArray[np.bool_]]:
    """One frame of :meth:`ContactTracker.update` from its traced chains and the
    previous frame's contacts (``before``).

    Returns:
        The frame's contacts, in ascending id; their origins (the previous id each
        keeps or split off, or -1), shape (C,); and over the previous contacts: the
        index here of the contact each merged into without keeping its id (or -1),
        and which are removed, shapes (P,).
    """
    found = components(
        chains, chain_bounds, settings.width, settings.min_area, settings.outline_passes
    )
    areas, bounds = found.areas, found.outlines.bounds
    count = len(areas)
    world_outlines, _ = orient_ccw_kernel(
        _to_world(found.outlines.points, settings.transform), bounds
    )
    outlines = Polylines(world_outlines, bounds)
    centroids = _to_world(found.centroids, settings.transform)
    prev_ids, prev_centroids, prev_contours = before.ids, before.centroids, before.contours
    keep, merged, parent = _match(
        _Contacts(prev_centroids, before.outlines), prev_ids,
        _Contacts(centroids, outlines), settings.radius,
    )  # fmt: skip
    # A continuing contour starts near its previous first point moved with the
    # centroid; fresh ids go to new contacts in raster order.
    starts = np.full((count, 2), np.nan)
    ids = np.empty(count, np.int64)
    origins = np.full(count, -1, np.int64)
    for c in range(count):
        p = keep[c]
        if p >= 0:
            first = prev_contours.points[prev_contours.bounds[p]]
            starts[c, 0] = first[0] + centroids[c, 0] - prev_centroids[p, 0]
            starts[c, 1] = first[1] + centroids[c, 1] - prev_centroids[p, 1]
            ids[c] = prev_ids[p]
            origins[c] = prev_ids[p]
        else:
            ids[c] = next_id
            next_id += 1
            if parent[c] >= 0:
                origins[c] = prev_ids[parent[c]]
    contours = resample_kernel(outlines, settings.spacing, starts)
    order = np.argsort(ids, kind="mergesort")
    rank = np.empty(count, np.intp)
    rank[order] = np.arange(count)
    removed = np.ones(len(prev_ids), np.bool_)
    for c in range(count):
        if keep[c] >= 0:
            removed[keep[c]] = False
    merged_into = np.full(len(prev_ids), -1, np.intp)
    for p in range(len(prev_ids)):
        if merged[p] >= 0:
            merged_into[p] = rank[merged[p]]
    sorted_outlines, outline_bounds = gather(world_outlines, bounds, order)
    sorted_contours, contour_bounds = gather(contours.points, contours.bounds, order)
    now = ContactSet(
        ids[order], keep[order] < 0, centroids[order], areas[order] * settings.pixel_area,
        Polylines(sorted_outlines, outline_bounds), Polylines(sorted_contours, contour_bounds),
    )  # fmt: skip
    return now, origins[order], merged_into, removed


@njit
def _to_world(pixels: NDArray[np.float64], transform: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pixel (column, row) points, shape (N, 2), in metres, world frame
    (``Surface.pixel_to_world``; ``transform`` is the tracker's ``(sx, sy, w, h)``)."""
    sx, sy, w, h = transform[0], transform[1], transform[2], transform[3]
    world = np.empty_like(pixels)
    for i in range(len(pixels)):
        world[i, 0] = (pixels[i, 0] + 0.5) * sx - 0.5 * w
        world[i, 1] = 0.5 * h - (pixels[i, 1] + 0.5) * sy
    return world


# At least this fraction of one outline inside the other makes two contacts overlap.
_OVERLAP = 0.25


class _Contacts(NamedTuple):
    """The contacts of one frame as the matching rules see them (compiled code only).

    Attributes:
        centroids: metres, world frame, shape (C, 2).
        outlines: the outlines, metres, world frame, one set per contact.
    """

    centroids: NDArray[np.float64]
    outlines: Polylines


class _ByX(NamedTuple):
    """Centroids in the order of their x, for the sweeps of the matching rules
    (compiled code only).

    Attributes:
        order: the centroids' indices, by x, shape (C,).
        xs: their x in that order, metres, shape (C,).
    """

    order: NDArray[np.intp]
    xs: NDArray[np.float64]


@njit
def _by_x(centroids: NDArray[np.float64]) -> _ByX:
    order = np.argsort(centroids[:, 0], kind="mergesort")
    return _ByX(order, centroids[order, 0])


@njit
def _match(
    before: _Contacts, prev_ids: NDArray[np.int64], now: _Contacts, radius: float
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """The module docstring's rules, from the previous frame's contacts (``before``,
    with their ids) to this frame's (``now``).

    Returns:
        (keep, merged, parent): for each current contact the previous contact
        (index) whose id it keeps, or -1, shape (C,); for each previous contact the
        current contact it merged into without keeping its id, or -1, shape (P,); for
        each new current contact the previous contact it split off, or -1, shape (C,).
    """
    prev_centroids, centroids = before.centroids, now.centroids
    n_prev, n_cur = len(prev_centroids), len(centroids)
    keep = np.full(n_cur, -1, np.intp)
    merged = np.full(n_prev, -1, np.intp)
    parent = np.full(n_cur, -1, np.intp)
    if n_prev == 0 or n_cur == 0:
        return keep, merged, parent
    prev_reach = reach_from(prev_centroids, before.outlines)
    reach = reach_from(centroids, now.outlines)
    sweep = _by_x(centroids)
    by_x, xs = sweep
    taken = np.zeros(n_prev, np.bool_)

    # 1. Motion: greedy one-to-one by distance, ties by previous id then raster.
    pair_p, pair_c, pair_d = _near_pairs(prev_centroids, centroids, sweep, radius)
    order = np.argsort(pair_c, kind="mergesort")
    order = order[np.argsort(prev_ids[pair_p[order]], kind="mergesort")]
    order = order[np.argsort(pair_d[order], kind="mergesort")]
    for k in order:
        p, c = pair_p[k], pair_c[k]
        if taken[p] or keep[c] >= 0:
            continue
        taken[p] = True
        keep[c] = p

    # 2. Merges: a leftover previous contact overlapping a current one goes to the
    # nearest such (ties: lower index).
    widest = reach.max()
    joined = np.full(n_prev, -1, np.intp)
    for p in np.argsort(prev_ids, kind="mergesort"):
        if taken[p]:
            continue
        best, best_d = -1, np.inf
        lo = np.searchsorted(xs, prev_centroids[p, 0] - prev_reach[p] - widest)
        hi = np.searchsorted(xs, prev_centroids[p, 0] + prev_reach[p] + widest, side="right")
        for s in range(lo, hi):
            c = by_x[s]
            d = _distance(prev_centroids[p], centroids[c])
            if d > prev_reach[p] + reach[c] or d > best_d or (d == best_d and c > best):
                continue
            if _overlap(before, p, now, c):
                best, best_d = c, d
        if best >= 0:
            joined[p] = best
            taken[p] = True
    for p in np.argsort(prev_ids, kind="mergesort"):
        c = joined[p]
        if c < 0:
            continue
        if keep[c] < 0:
            # The nearest previous contact that merged into it keeps its id (ties:
            # lower id); it is the first in id order at the smallest distance.
            nearest, nearest_d = -1, np.inf
            for q in np.argsort(prev_ids, kind="mergesort"):
                if joined[q] == c:
                    d = _distance(prev_centroids[q], centroids[c])
                    if d < nearest_d:
                        nearest, nearest_d = q, d
            keep[c] = nearest
        if keep[c] != p:
            merged[p] = c

    # 3. Splits: a leftover current contact overlapping a previous one split off the
    # nearest such (ties: lower id).
    by_px, pxs = _by_x(prev_centroids)
    prev_widest = prev_reach.max()
    for c in range(n_cur):
        if keep[c] >= 0:
            continue
        best, best_d, best_id = -1, np.inf, np.int64(0)
        lo = np.searchsorted(pxs, centroids[c, 0] - reach[c] - prev_widest)
        hi = np.searchsorted(pxs, centroids[c, 0] + reach[c] + prev_widest, side="right")
        for s in range(lo, hi):
            p = by_px[s]
            d = _distance(prev_centroids[p], centroids[c])
            if d > prev_reach[p] + reach[c]:
                continue
            if best >= 0 and (d > best_d or (d == best_d and prev_ids[p] >= best_id)):
                continue
            if _overlap(before, p, now, c):
                best, best_d, best_id = p, d, prev_ids[p]
        parent[c] = best
    return keep, merged, parent


@njit
def _distance(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    return float(np.hypot(a[0] - b[0], a[1] - b[1]))


@njit
def _near_pairs(
    prev_centroids: NDArray[np.float64], centroids: NDArray[np.float64], sweep: _ByX, radius: float
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """(previous, current, distance) of every pair of centroids at most ``radius``
    apart, found by a sweep over the current centroids sorted by x (``sweep``)."""
    by_x, xs = sweep
    ranges = np.empty((len(prev_centroids), 2), np.intp)
    total = 0
    for p in range(len(prev_centroids)):
        ranges[p, 0] = np.searchsorted(xs, prev_centroids[p, 0] - radius)
        ranges[p, 1] = np.searchsorted(xs, prev_centroids[p, 0] + radius, side="right")
        total += ranges[p, 1] - ranges[p, 0]
    pair_p = np.empty(total, np.intp)
    pair_c = np.empty(total, np.intp)
    pair_d = np.empty(total)
    n = 0
    for p in range(len(prev_centroids)):
        for s in range(ranges[p, 0], ranges[p, 1]):
            c = by_x[s]
            d = _distance(prev_centroids[p], centroids[c])
            if d <= radius:
                pair_p[n], pair_c[n], pair_d[n] = p, c, d
                n += 1
    return pair_p[:n], pair_c[:n], pair_d[:n]


@njit
def _overlap(before: _Contacts, p: int, now: _Contacts, c: int) -> bool:
    """Whether previous contact p and current contact c overlap (module docstring)."""
    mine = before.outlines.points[before.outlines.bounds[p] : before.outlines.bounds[p + 1]]
    theirs = now.outlines.points[now.outlines.bounds[c] : now.outlines.bounds[c + 1]]
    if _inside(now.centroids[c, 0], now.centroids[c, 1], mine):
        return True
    if _inside(before.centroids[p, 0], before.centroids[p, 1], theirs):
        return True
    return _share_inside(mine, theirs) >= _OVERLAP or _share_inside(theirs, mine) >= _OVERLAP


@njit
def _share_inside(points: NDArray[np.float64], polygon: NDArray[np.float64]) -> float:
    """Fraction of ``points`` (K, 2) inside the closed ``polygon`` (L, 2)."""
    inside = 0
    for k in range(len(points)):
        if _inside(points[k, 0], points[k, 1], polygon):
            inside += 1
    return inside / len(points)


@njit
def _inside(x: float, y: float, polygon: NDArray[np.float64]) -> bool:
    """Whether (x, y) lies inside the closed polygon (L, 2), same frame; even-odd."""
    crossings = 0
    n = len(polygon)
    for i in range(n):
        xi, yi = polygon[i, 0], polygon[i, 1]
        j = i + 1 if i + 1 < n else 0
        xj, yj = polygon[j, 0], polygon[j, 1]
        if (yi > y) != (yj > y) and x < xi + (y - yi) * (xj - xi) / (yj - yi):
            crossings += 1
    return crossings % 2 == 1
