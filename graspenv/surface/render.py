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


def _repeated_vertices(
    polygons: NDArray[np.float64], counts: NDArray[np.intp]
) -> NDArray[np.bool_] | None:
    """Which vertices coincide (to 1e-6 px) with the next of their polygon; None if
    none do."""
    following = np.arange(1, len(polygons) + 1)
    ends = np.cumsum(counts)[counts > 0]
    following[ends - 1] = ends - counts[counts > 0]
    repeated = np.abs(polygons[following] - polygons).max(axis=1) <= 1e-6
    return repeated if repeated.any() else None


def _inset(
    polygons: NDArray[np.float64], starts: NDArray[np.intp], distance: float
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Move the edges of closed polygons inward by ``distance`` (miter joins).

    Args:
        polygons: the vertices of all polygons, one after the other, shape (N, 2).
        starts: index of each polygon's first vertex, increasing, shape (K,).
        distance: how far to move each edge, in the units of ``polygons``.

    Returns:
        the moved vertices, shape (N, 2), and for each polygon whether it survived
        (False when it is empty or too thin: its orientation flips), shape (K,).
    """
    n = len(polygons)
    ends = np.append(starts[1:], n)
    following = np.arange(1, n + 1)
    following[ends - 1] = starts
    preceding = np.arange(-1, n - 1)
    preceding[starts] = ends - 1

    def doubled_areas(points: NDArray[np.float64]) -> NDArray[np.float64]:
        x, y = points[:, 0], points[:, 1]
        cross = x * y[following] - x[following] * y
        result: NDArray[np.float64] = np.add.reduceat(cross, starts)
        return result

    area = doubled_areas(polygons)
    edge = polygons[following] - polygons
    length = np.hypot(edge[:, 0], edge[:, 1])
    # For a positive (counter-clockwise in x-right, y-up terms) polygon the outward
    # normal is the tangent turned clockwise; the sign of the area covers both.
    sign = np.repeat(np.sign(area), ends - starts) / np.where(length > 0.0, length, 1.0)
    outward = np.stack([edge[:, 1] * sign, -edge[:, 0] * sign], axis=-1)
    incoming = outward[preceding]
    total = outward + incoming
    scale = 1.0 + np.einsum("ij,ij->i", outward, incoming)
    moved = polygons - total * (distance / np.maximum(scale, 2.0 / _MITER_LIMIT**2))[:, None]
    survived = (area * doubled_areas(moved) > 0.0) & (ends > starts)
    return moved, survived


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
    height, width = surface.shape
    coverage = np.zeros((height, width), dtype=np.uint8)
    shapes = _on_table(_shapes_of(hand_or_shapes), surface)
    if not shapes:
        return coverage
    max_segment = _MAX_SEGMENT_PX * float(surface.pixel_size.min())
    outlines = [shape.outline(max_segment) for shape in shapes]
    counts = np.array([len(outline) for outline in outlines])
    # One conversion and one inset for all shapes: per-call overhead dominates here.
    pixels = surface.world_to_pixel(np.concatenate(outlines))
    repeated = _repeated_vertices(pixels, counts)
    if repeated is not None:
        # A zero-length edge has no normal, so the inset would leave its corner put.
        owner = np.repeat(np.arange(len(counts)), counts)
        pixels, counts = pixels[~repeated], np.bincount(owner[~repeated], minlength=len(counts))
    drawable = counts >= 3
    if not drawable.all():
        # Degenerate outlines would make reduceat misbehave; they cover nothing anyway.
        pixels, counts = pixels[np.repeat(drawable, counts)], counts[drawable]
        if len(counts) == 0:
            return coverage
    starts = np.cumsum(counts) - counts
    pixels, survived = _inset(pixels, starts, AA_EDGE_BIAS)
    low = np.floor(np.minimum.reduceat(pixels, starts)).astype(int) - _MARGIN
    high = np.ceil(np.maximum.reduceat(pixels, starts)).astype(int) + _MARGIN
    low = np.maximum(low, 0)
    high = np.minimum(high, (width - 1, height - 1))
    scale = float(1 << _SHIFT)
    for i in range(len(counts)):
        (c0, r0), (c1, r1) = low[i].tolist(), high[i].tolist()
        if not survived[i] or c0 > c1 or r0 > r1:
            continue  # thinner than the inset, or wholly off the table
        # Coordinates relative to the clipped region; OpenCV clips what falls outside.
        relative = (pixels[starts[i] : starts[i] + counts[i]] - (c0, r0)) * scale
        region = np.zeros((r1 - r0 + 1, c1 - c0 + 1), dtype=np.uint8)
        cv2.fillPoly(region, [np.round(relative).astype(np.int32)], 255, cv2.LINE_AA, _SHIFT)
        window = coverage[r0 : r1 + 1, c0 : c1 + 1]
        np.maximum(window, region, out=window)
    return coverage


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
    mask = render_coverage(hand_or_shapes, surface)
    # In place: a freshly allocated full-frame output costs more than the drawing.
    cv2.threshold(mask, 127, 255, cv2.THRESH_BINARY, dst=mask)
    if noise is not None and noise.enabled:
        return noise.apply(mask, rng)
    return mask
