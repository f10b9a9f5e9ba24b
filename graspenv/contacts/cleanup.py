"""A noisy table's mask cleaned before its contacts are traced: each pixel voted on
over the last masks (``contacts.vote_frames``), a closing (``close_px``) and the
last frame's dropouts filled (``fill_px``); all three off by default.

:class:`MaskCleaner` keeps what the vote and the fill remember from frame to frame.
A frame's work is a few whole-image OpenCV calls (the running vote count, its
threshold, a labelling of the mask, the closing, a dilation) and one compiled pass
for the components' areas and boxes; what is done per component is done inside its
own box, and only for the few components it concerns: the fingers the vote would
cut (rarely any), the components big enough not to be specks. A mask of sensor
noise has hundreds of specks and a handful of fingers, and a whole-image lookup or
count by label costs about a millisecond at 640 × 480, ten times a clean frame's
tracing.
"""

from __future__ import annotations

import math
from collections import deque

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.config import ContactConfig
from graspenv.jit import njit

__all__ = ["VOTE_KEEPS", "MaskCleaner"]

#: A component of a frame's mask of which the vote (``contacts.vote_frames``) keeps
#: less than this share is taken as it is. The vote keeps a still fingertip under a
#: pixel of edge jitter nearly whole, and a round one moving a quarter of its width
#: a frame about two thirds (it lags a frame); from about two fifths of its width a
#: frame it would keep less than half, cut into slivers or erased.
VOTE_KEEPS = 0.5

# Beyond this many components to visit one by one, a whole-image lookup by label is
# the cheaper (a frame of hundreds of fingertips).
_ONE_BY_ONE = 32

Mask = NDArray[np.uint8]


@njit
def _areas_and_boxes(
    labels: NDArray[np.int32], count: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Each label's pixel count and box (first row, first column, last row, last
    column), one pass over the labels; the background's (label 0) count is 0.
    OpenCV's labelling with statistics takes six times as long as without them
    (0.65 against 0.1 ms at 640 × 480), most of it the centroids, not needed here."""
    area = np.zeros(count, np.int64)
    box = np.empty((count, 4), np.int64)
    rows, cols = labels.shape
    box[:, 0] = rows
    box[:, 1] = cols
    box[:, 2] = -1
    box[:, 3] = -1
    for r in range(rows):
        for c in range(cols):
            label = labels[r, c]
            if label == 0:
                continue
            area[label] += 1
            box[label, 0] = min(box[label, 0], r)
            box[label, 1] = min(box[label, 1], c)
            box[label, 2] = max(box[label, 2], r)
            box[label, 3] = max(box[label, 3], c)
    return area, box


class _Labels:
    """One labelling of a 0/1 mask: its components' labels, areas and boxes."""

    def __init__(self, mask: Mask) -> None:
        count, labels = cv2.connectedComponents(mask, connectivity=8)
        self.count: int = count
        self.labels: NDArray[np.int32] = np.asarray(labels, np.int32)
        self.area, self.boxes = _areas_and_boxes(self.labels, self.count)

    def window(self, label: int) -> tuple[slice, slice]:
        top, left, bottom, right = self.boxes[label].tolist()
        return slice(top, bottom + 1), slice(left, right + 1)

    def select(self, which: NDArray[np.bool_]) -> Mask:
        """The components ``which`` marks (by label), as a 0/1 mask."""
        chosen = np.flatnonzero(which)
        if len(chosen) > _ONE_BY_ONE:
            return np.asarray(which[self.labels], np.uint8)
        out = np.zeros(self.labels.shape, np.uint8)
        for label in chosen.tolist():
            rows, cols = self.window(label)
            out[rows, cols][self.labels[rows, cols] == label] = 1
        return out

    def counts_in(self, mask: Mask, which: NDArray[np.bool_]) -> NDArray[np.int64]:
        """How many pixels of ``mask`` each component ``which`` marks holds (0 for
        the others)."""
        counts = np.zeros(self.count, np.int64)
        chosen = np.flatnonzero(which)
        if len(chosen) > _ONE_BY_ONE:
            counts[:] = np.bincount(self.labels[mask != 0], minlength=self.count)
            counts[~which] = 0
            return counts
        for label in chosen.tolist():
            rows, cols = self.window(label)
            counts[label] = np.count_nonzero(mask[rows, cols][self.labels[rows, cols] == label])
        return counts


class MaskCleaner:
    """The clean-ups ``config`` asks for, frame after frame.

    Args:
        config: ``vote_frames``, ``close_px`` and ``fill_px`` say what is done.
        min_area: the smallest component that is not a speck, pixels (the vote
            and the fill leave specks to themselves).
    """

    def __init__(self, config: ContactConfig, min_area: float) -> None:
        self.config = config
        self._min_area = min_area
        close, fill = config.close_px, config.fill_px
        self._close = (
            cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close, close)) if close > 1 else None
        )
        self._fill = (
            cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * fill + 1, 2 * fill + 1))
            if fill > 0
            else None
        )
        #: Whether the configuration cleans at all (a clean table's mask is traced
        #: as it comes).
        self.needed = config.vote_frames > 1 or self._close is not None or self._fill is not None
        # The last vote_frames masks as they came (oldest first) and their sum.
        self._recent: deque[Mask] = deque(maxlen=config.vote_frames)
        self._votes: Mask | None = None
        self._last_seen: Mask | None = None

    def reset(self) -> None:
        """Forget the masks seen so far."""
        self._recent.clear()
        self._votes = None
        self._last_seen = None

    def __call__(self, image: NDArray[np.bool_] | Mask) -> Mask:
        """The mask voted on over the last frames (``vote_frames``), closed
        (``close_px``) and its dropouts filled (``fill_px``), 0 or 1: a new array,
        which the caller may change. ``image`` (2-D, bool or uint8, non-zero =
        touched, as :func:`~graspenv.contacts.extract.validate_mask` gives it) is not
        changed."""
        touched: Mask = image.view(np.uint8)  # a bool mask's bytes are 0 or 1
        clean: Mask = np.asarray(cv2.threshold(touched, 0, 1, cv2.THRESH_BINARY)[1], np.uint8)
        if self.config.vote_frames > 1:
            clean = self._voted(clean)
        if self._close is not None:
            clean = np.asarray(cv2.morphologyEx(clean, cv2.MORPH_CLOSE, self._close), np.uint8)
        if self._fill is not None:
            # Fill this frame's dropouts from the last frame's mask, but only within
            # fill_px of what is touched now (a lifted finger is not kept), specks
            # aside: a flipped pixel beside a lifted finger would keep a piece of it.
            seen = clean
            if self._last_seen is not None:
                near = np.asarray(cv2.dilate(self._without_specks(clean), self._fill), np.uint8)
                clean = np.asarray(
                    cv2.bitwise_or(clean, cv2.bitwise_and(self._last_seen, near)), np.uint8
                )
            self._last_seen = seen.copy() if seen is clean else seen
        return clean

    def _without_specks(self, touched: Mask) -> Mask:
        """``touched`` (0 or 1) without its components of fewer than ``min_area``
        pixels."""
        if self._min_area <= 1.0:
            return touched
        parts = _Labels(touched)
        kept = parts.area >= self._min_area
        if np.count_nonzero(kept) == parts.count - 1:  # no specks
            return touched
        return parts.select(kept)

    def _count_votes(self, touched: Mask) -> int:
        """Add ``touched`` to the last masks and their running sum; how many there
        are now."""
        recent = self._recent
        oldest = recent[0] if len(recent) == recent.maxlen else None
        recent.append(touched)
        if self._votes is None:
            self._votes = touched.copy()
        else:
            self._votes = np.asarray(cv2.add(self._votes, touched), np.uint8)
            if oldest is not None:
                self._votes = np.asarray(cv2.subtract(self._votes, oldest), np.uint8)
        return len(recent)

    def _voted(self, touched: Mask) -> Mask:
        """Each pixel touched in most of the last ``vote_frames`` masks (``touched``
        the newest, 0 or 1), but for the components of ``touched`` of at least
        ``min_area`` of which the vote keeps less than :data:`VOTE_KEEPS`: a finger
        that just touched down, or one that moved more than about two fifths of its
        width since the last frame, which the vote would erase or cut into slivers.
        Each of those is taken as it is, and the voted pixels where it was (within
        twice its width, in no part of a contact the vote keeps) are dropped."""
        seen = self._count_votes(touched)
        if seen == 1:
            return touched.copy()  # the vote keeps touched itself
        assert self._votes is not None
        voted: Mask = np.asarray(
            cv2.threshold(self._votes, seen // 2, 1, cv2.THRESH_BINARY)[1], np.uint8
        )
        parts = _Labels(touched)
        # Specks are left to the vote: taken as they are, a flipped pixel beside a
        # finger that lifted would drop that finger's last voted frame alone.
        big = parts.area >= self._min_area
        big[0] = False
        moved = big & (parts.counts_in(voted, big) < VOTE_KEEPS * parts.area)
        if not moved.any():
            return voted
        labels = parts.labels
        as_seen = parts.select(moved)
        reach = 2 * round(2.0 * math.sqrt(float(parts.area[moved].max()))) + 1
        trail = cv2.dilate(as_seen, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (reach, reach)))
        is_voted, is_seen = voted != 0, as_seen != 0
        count, where = cv2.connectedComponents(voted, connectivity=8)
        steady = np.zeros(count, bool)
        steady[where[is_voted & (labels > 0) & ~is_seen]] = True
        left = np.zeros(count, bool)
        left[where[is_voted & (trail != 0)]] = True
        left &= ~steady
        left[0] = False
        return np.asarray(is_voted & ~left[where] | is_seen, np.uint8)
