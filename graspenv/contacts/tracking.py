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

A continuing contact's contour starts at the point of its outline closest to its
previous contour's first point moved by the centroid's displacement, so index 0 does
not jump around the contour from frame to frame; a new contact's contour starts at
its outline's first point (near its top-left pixel). Contacts in a frame are listed in
ascending id.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ContactConfig
from graspenv.contacts.extract import find_components_batch, validate_mask
from graspenv.contacts.resample import orient_ccw_batch, resample_closed_batch
from graspenv.surface.geometry import Surface

__all__ = ["Contact", "ContactFrame", "ContactStatus", "ContactTracker"]

ContactStatus = Literal["new", "continuing"]


def _frozen(array: NDArray[np.float64]) -> NDArray[np.float64]:
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


@dataclass(frozen=True, eq=False)
class ContactFrame:
    """The contacts of one camera frame.

    Attributes:
        index: frames since the tracker was created or reset, from 0.
        contacts: the contacts present, in ascending id.
        removed: ids present in the previous frame and gone now (lift-offs and
            contacts merged into another), ascending.
    """

    index: int
    contacts: tuple[Contact, ...]
    removed: tuple[int, ...]

    @property
    def ids(self) -> tuple[int, ...]:
        """Ids of the contacts present, ascending."""
        return tuple(c.id for c in self.contacts)

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
        for contact in self.contacts:
            if contact.id == contact_id:
                return contact
        return None

    def __getitem__(self, contact_id: int) -> Contact:
        contact = self.get(contact_id)
        if contact is None:
            raise KeyError(f"no contact with id {contact_id} in frame {self.index}")
        return contact

    def __contains__(self, contact_id: object) -> bool:
        return any(c.id == contact_id for c in self.contacts)

    def __iter__(self) -> Iterator[Contact]:
        return iter(self.contacts)

    def __len__(self) -> int:
        return len(self.contacts)


@dataclass(frozen=True, eq=False)
class _Blob:
    """A component of the current mask in world units, before it has an id."""

    outline: NDArray[np.float64]
    centroid: NDArray[np.float64]
    area: float


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
        self._previous: tuple[Contact, ...] = ()
        self._next_id = 0
        self._index = 0

    def reset(self) -> None:
        """Forget all contacts; ids and the frame index start again from 0."""
        self._previous = ()
        self._next_id = 0
        self._index = 0

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
        blobs, outlines, bounds = self._blobs(image)
        keeps, sources = self._match(self._previous, blobs)

        by_id = {c.id: c for c in self._previous}
        # Every contour of the frame in one pass; a continuing one starts near its
        # previous first point moved with the centroid.
        starts = np.full((len(blobs), 2), np.nan)
        for i, kept in enumerate(keeps):
            if kept is not None:
                before = by_id[kept]
                starts[i] = before.contour[0] + (blobs[i].centroid - before.centroid)
        contours: list[NDArray[np.float64]] = []
        if blobs:
            resampled, cuts = resample_closed_batch(outlines, bounds, self._spacing, starts)
            contours = [resampled[cuts[i] : cuts[i + 1]] for i in range(len(blobs))]
        contacts: list[Contact] = []
        for i, blob in enumerate(blobs):
            kept = keeps[i]
            if kept is not None:
                contact_id = kept
            else:
                contact_id = self._next_id
                self._next_id += 1
            contacts.append(
                Contact(
                    id=contact_id,
                    contour=_frozen(contours[i]),
                    outline=_frozen(blob.outline),
                    centroid=_frozen(blob.centroid),
                    area=blob.area,
                    status="continuing" if kept is not None else "new",
                    sources=sources[i],
                )
            )
        contacts.sort(key=lambda c: c.id)
        kept_ids = {k for k in keeps if k is not None}
        removed = tuple(sorted(c.id for c in self._previous if c.id not in kept_ids))
        frame = ContactFrame(self._index, tuple(contacts), removed)
        self._previous = frame.contacts
        self._index += 1
        return frame

    def _blobs(
        self, image: NDArray[np.uint8]
    ) -> tuple[list[_Blob], NDArray[np.float64], NDArray[np.intp]]:
        """The mask's components in world units, outlines counter-clockwise: one
        transform for every outline and centroid of the frame.

        Returns:
            (blobs, outlines, bounds): the blobs, whose outlines are views of
            ``outlines`` (all of them one after another, metres, world frame), blob i's
            being ``outlines[bounds[i]:bounds[i + 1]]``.
        """
        components, pixels, bounds = find_components_batch(image, self.config.min_area)
        if not components:
            return [], np.zeros((0, 2)), bounds
        total = len(pixels)
        world = self.surface.pixel_to_world(
            np.concatenate([pixels, [c.centroid for c in components]])
        )
        outlines = orient_ccw_batch(world[:total], bounds)
        blobs = [
            _Blob(outlines[bounds[i] : bounds[i + 1]], world[total + i], c.area * self._pixel_area)
            for i, c in enumerate(components)
        ]
        return blobs, outlines, bounds

    def _match(
        self, previous: tuple[Contact, ...], blobs: list[_Blob]
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
        p_idx, c_idx = np.nonzero(distance <= self.config.match_radius)
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


# At least this fraction of one outline inside the other makes two contacts overlap.
_OVERLAP = 0.25


def _overlap(centroid: NDArray[np.float64], outline: NDArray[np.float64], blob: _Blob) -> bool:
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
