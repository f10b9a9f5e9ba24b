"""Contact masks from contact shapes: what the table's camera sees.

Each touching shape's outline is filled with OpenCV's anti-aliased polygon fill at
sub-pixel precision (fixed-point ``shift`` bits) into a coverage image; the union of
the shapes is their pixel-wise maximum, and a pixel is touched where the coverage is
at least one half. Only a small region around each shape is drawn.

OpenCV's anti-aliased fill is not an area coverage: it paints a one-pixel-wide
anti-aliased line along the outline over the filled polygon, so thresholding its
output at one half would grow every shape by about 0.6 pixels (more along diagonal
edges and where the outline has more vertices). The outline is therefore moved inward
by :data:`AA_EDGE_BIAS` pixels before filling, which leaves the mask unbiased on
average and within about 0.25 pixels of the exact one (the pixels whose centres lie
inside the shape) everywhere; ``tests/surface/test_render.py`` checks both. Shapes or
parts narrower than about 1.5 pixels are not drawn reliably, and the tips of corners
sharper than about 60° may overshoot by up to half a pixel more.
"""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.geometry import Polylines, bounds_of
from graspenv.jit import njit
from graspenv.surface.geometry import Surface
from graspenv.surface.hand import Hand
from graspenv.surface.noise import SensorNoise
from graspenv.surface.shapes import ContactShape

__all__ = ["AA_EDGE_BIAS", "render_coverage", "render_mask"]

#: Pixels by which OpenCV's anti-aliased fill of an outline sampled every pixel,
#: thresholded at one half, extends past the true outline: the mean over edge
#: directions and sub-pixel phases (tied to ``_MAX_SEGMENT_PX``; measure both together).
AA_EDGE_BIAS = 0.62

# Fixed-point fraction bits of vertex coordinates: 1/256 pixel.
_SHIFT = 8
# Longest outline edge in pixels: the chord of a 3-pixel fingertip then strays
# 0.04 px from the ellipse; shorter edges cost time and change the bias above.
_MAX_SEGMENT_PX = 1.0
# Margin around a shape's pixel bounding box, for the anti-aliased border.
_MARGIN = 2
# Larger shapes would take millions of outline vertices and overflow the fixed-point
# coordinates (2**16 pixels times 2**_SHIFT stays well inside 32 bits).
_MAX_RADIUS_PX = 1 << 16
# A corner's miter may move its vertex at most this many times the inset.
_MITER_LIMIT = 4.0


def _shapes_of(hand_or_shapes: Hand | ContactShape | Iterable[ContactShape]) -> list[ContactShape]:
    if isinstance(hand_or_shapes, Hand):
        return hand_or_shapes.touching_shapes()
    if isinstance(hand_or_shapes, ContactShape):
        return [hand_or_shapes]
    shapes = list(hand_or_shapes)
    for i, shape in enumerate(shapes):
        if not isinstance(shape, ContactShape):
            raise ValueError(
                f"hand_or_shapes[{i}] must be a ContactShape, got {type(shape).__name__}"
            )
    return shapes


def _on_table(shapes: list[ContactShape], surface: Surface) -> list[ContactShape]:
    """The shapes that may cover a pixel; ValueError for one too large to draw."""
    if not shapes:
        return shapes
    height, width = surface.shape
    centres = surface.world_to_pixel(np.array([shape.centre for shape in shapes]))
    radii = np.array([shape.bounding_radius for shape in shapes]) / surface.pixel_size.min()
    nearest = np.clip(centres, -0.5, (width - 0.5, height - 0.5))
    reach = np.hypot(*(centres - nearest).T) - radii
    for shape, radius, gap in zip(shapes, radii, reach, strict=True):
        if radius > _MAX_RADIUS_PX and gap < _MARGIN:
            raise ValueError(
                f"{shape!r} spans {radius:.0f} pixels from its centre; at most "
                f"{_MAX_RADIUS_PX} can be drawn"
            )
    return [shape for shape, gap in zip(shapes, reach, strict=True) if gap < _MARGIN]


@njit
def _inset_polygons(
    outlines: Polylines, distance: float, margin: int, width: int, height: int, scale: float
) -> tuple[NDArray[np.int32], NDArray[np.intp], NDArray[np.int64]]:
    """Every shape's outline (pixels (column, row)) moved inward by ``distance``
    (miter joins), in fixed point.

    A vertex that coincides (to 1e-6 px) with the next has no edge normal, so it is
    dropped first (the inset would leave its corner put), and outlines of fewer than
    three vertices cover nothing. A polygon whose orientation flips is thinner than
    the inset and is dropped too.

    Returns:
        (polygons, bounds, boxes): each polygon's vertices relative to its region's
        top-left pixel times ``scale``, rounded, int32, laid end to end with bounds;
        and each region (c0, r0, c1, r1) on the image with ``margin`` pixels around
        the polygon, -1 rows for polygons not drawn.
    """
    pixels, starts = outlines
    count = len(starts) - 1
    keep = np.zeros(len(pixels), np.bool_)
    sizes = np.zeros(count, np.intp)
    for c in range(count):
        lo, hi = starts[c], starts[c + 1]
        for i in range(lo, hi):
            j = i + 1 if i + 1 < hi else lo
            gap = max(abs(pixels[j, 0] - pixels[i, 0]), abs(pixels[j, 1] - pixels[i, 1]))
            keep[i] = gap > 1e-6
            sizes[c] += keep[i]
    bounds = np.zeros(count + 1, np.intp)
    bounds[1:] = np.cumsum(sizes)
    points = pixels[keep]
    moved = np.empty_like(points)
    boxes = np.full((count, 4), -1, np.int64)
    out = np.empty((len(points), 2), np.int32)
    floor_scale = 2.0 / _MITER_LIMIT**2
    for c in range(count):
        lo, hi = bounds[c], bounds[c + 1]
        n = hi - lo
        if n < 3:
            continue
        area = 0.0
        for i in range(lo, hi):
            j = i + 1 if i + 1 < hi else lo
            area += points[i, 0] * points[j, 1] - points[j, 0] * points[i, 1]
        # For a positive (counter-clockwise in x-right, y-up terms) polygon the
        # outward normal is the tangent turned clockwise; the sign of the area covers
        # both.
        for i in range(lo, hi):
            j = i + 1 if i + 1 < hi else lo
            before = i - 1 if i > lo else hi - 1
            ex, ey = points[j, 0] - points[i, 0], points[j, 1] - points[i, 1]
            bx, by = points[i, 0] - points[before, 0], points[i, 1] - points[before, 1]
            length = np.hypot(ex, ey)
            before_length = np.hypot(bx, by)
            sign = np.sign(area) / (length if length > 0.0 else 1.0)
            before_sign = np.sign(area) / (before_length if before_length > 0.0 else 1.0)
            ox, oy = ey * sign, -ex * sign
            ix, iy = by * before_sign, -bx * before_sign
            spread = 1.0 + (ox * ix + oy * iy)
            step = distance / max(spread, floor_scale)
            moved[i, 0] = points[i, 0] - (ox + ix) * step
            moved[i, 1] = points[i, 1] - (oy + iy) * step
        moved_area = 0.0
        for i in range(lo, hi):
            j = i + 1 if i + 1 < hi else lo
            moved_area += moved[i, 0] * moved[j, 1] - moved[j, 0] * moved[i, 1]
        if not area * moved_area > 0.0:
            continue  # thinner than the inset
        c0 = max(int(np.floor(moved[lo:hi, 0].min())) - margin, 0)
        r0 = max(int(np.floor(moved[lo:hi, 1].min())) - margin, 0)
        c1 = min(int(np.ceil(moved[lo:hi, 0].max())) + margin, width - 1)
        r1 = min(int(np.ceil(moved[lo:hi, 1].max())) + margin, height - 1)
        if c0 > c1 or r0 > r1:
            continue  # wholly off the table
        boxes[c, 0], boxes[c, 1], boxes[c, 2], boxes[c, 3] = c0, r0, c1, r1
        # Coordinates relative to the region; OpenCV clips what falls outside.
        for i in range(lo, hi):
            out[i, 0] = np.int32(np.round((moved[i, 0] - c0) * scale))
            out[i, 1] = np.int32(np.round((moved[i, 1] - r0) * scale))
    return out, bounds, boxes


def _draw(
    hand_or_shapes: Hand | ContactShape | Iterable[ContactShape],
    surface: Surface,
    threshold: bool,
) -> NDArray[np.uint8]:
    """The anti-aliased fill of every touching shape, union by maximum, each region
    thresholded at one half first when ``threshold`` (the same mask as thresholding
    the union, since a threshold keeps the order of values)."""
    height, width = surface.shape
    image = np.zeros((height, width), dtype=np.uint8)
    shapes = _on_table(_shapes_of(hand_or_shapes), surface)
    if not shapes:
        return image
    max_segment = _MAX_SEGMENT_PX * float(surface.pixel_size.min())
    outlines = [shape.outline(max_segment) for shape in shapes]
    # One conversion and one compiled inset for all shapes: per-call overhead
    # dominates here.
    in_pixels = Polylines(
        surface.world_to_pixel(np.concatenate(outlines)),
        bounds_of([len(outline) for outline in outlines]),
    )
    polygons, bounds, boxes = _inset_polygons(
        in_pixels, AA_EDGE_BIAS, _MARGIN, width, height, float(1 << _SHIFT)
    )
    for i, (c0, r0, c1, r1) in enumerate(boxes.tolist()):
        if c0 < 0:
            continue
        region = np.zeros((r1 - r0 + 1, c1 - c0 + 1), dtype=np.uint8)
        cv2.fillPoly(region, [polygons[bounds[i] : bounds[i + 1]]], 255, cv2.LINE_AA, _SHIFT)
        if threshold:
            cv2.threshold(region, 127, 255, cv2.THRESH_BINARY, dst=region)
        window = image[r0 : r1 + 1, c0 : c1 + 1]
        np.maximum(window, region, out=window)
    return image


def render_coverage(
    hand_or_shapes: Hand | ContactShape | Iterable[ContactShape],
    surface: Surface,
) -> NDArray[np.uint8]:
    """The anti-aliased image of the touching shapes, before thresholding.

    Args:
        hand_or_shapes: a Hand (only its touching shapes are drawn), one shape, or
            shapes.
        surface: the table, its size and camera resolution.

    Returns:
        shape (H, W), uint8: 0 where nothing touches, 255 well inside a shape, and
        in between along the (inset) edges; union over shapes by maximum.

    Raises:
        ValueError: an item is not a ContactShape, or a shape that reaches the table
            spans more than 65 536 pixels from its centre.
    """
    return _draw(hand_or_shapes, surface, threshold=False)


def render_mask(
    hand_or_shapes: Hand | ContactShape | Iterable[ContactShape],
    surface: Surface,
    noise: SensorNoise | None = None,
    rng: np.random.Generator | None = None,
) -> NDArray[np.uint8]:
    """The contact mask the table sees.

    A pixel is touched where at least half of it is covered by a touching shape
    (within about 0.25 pixel), before noise.

    Args:
        hand_or_shapes: a Hand (only its touching shapes are drawn), one shape, or
            shapes.
        surface: the table, its size and camera resolution.
        noise: sensor noise added to the mask; None adds none.
        rng: random generator for the noise, required when it draws random numbers.

    Returns:
        shape (H, W), uint8, 255 where touched and 0 elsewhere (non-zero = touched is
        the contract).

    Raises:
        ValueError: an item is not a ContactShape, or ``rng`` is missing for random
            noise.
    """
    # Each drawn region is thresholded on its own: the whole frame would cost more
    # than the drawing.
    mask = _draw(hand_or_shapes, surface, threshold=True)
    if noise is not None and noise.enabled:
        return noise.apply(mask, rng)
    return mask
