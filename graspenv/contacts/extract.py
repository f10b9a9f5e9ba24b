"""Connected components of a contact mask and their outer outlines, in pixels.

One pass of OpenCV's border following (``cv2.findContours`` with ``RETR_EXTERNAL``
and ``CHAIN_APPROX_NONE``) gives every component's outer boundary; its contour
moments, computed as ``cv2.moments`` computes them, give its area and centroid. This
is far cheaper than labelling the image (``connectedComponentsWithStats``) and is
what the tracker runs every frame.

Pixel frame: (column, row), pixel centres at integers, rows going down (see
:class:`graspenv.surface.geometry.Surface`).

**Half-pixel outline offset.** OpenCV traces the centres of the boundary pixels. For
a shape rasterised by its pixel centres (a camera image thresholded at half coverage
is close to that), the true edge lies on average half a pixel beyond those centres
along the dominant axis of the edge's normal: the gap between the last covered centre
and the edge is uniform in [0, 1) pixel along the row or column that crosses the edge
most steeply, so 0.5·max(|n_x|, |n_y|) pixels along the unit normal n.
:func:`outline_from_chain` moves every traced point outward by exactly that, along
the normal of the chord between its two neighbours (0.5 px where the boundary runs
along a row or column, 0.5/√2 px where it runs diagonally). Where the chain doubles
back (the end of a one-pixel-wide line or spur) it puts the two corners of a square
cap half a pixel beyond the end pixel, and a single pixel becomes its square
footprint, so every outline encloses a positive area. Outlines of eight points or
more are then smoothed once by [-1, 4, 10, 4, -1] / 16, which removes the pixel
staircase (otherwise 5 % longer than the edge and a cause of uneven resampling)
without shrinking curves. Outlines of sixteen points or more may then be smoothed by
``contacts.outline_smoothing`` pairs of Taubin's shrink-free passes (none at the
default, six at the ``reference`` preset; :func:`_taubin`), which damp the
staircase's remaining one- to three-pixel ripple: a contour sampled finer than a
few pixels would otherwise follow it point by point, and it changes every frame as
the fingers cross the pixels.

Measured against the analytic boundary of 400 random ellipses with 6.3-12.6 px
semi-axes (6-12 mm fingertips on the default table): signed distance of outline
vertices and edge midpoints in pixels, and outline length over the true perimeter
(``python -m graspenv.bench.outline``):

================  ===========  ========  =======  ===========  ==========
mask rendered by  outline      mean      RMS      largest |.|  length
================  ===========  ========  =======  ===========  ==========
pixel centres     traced       -0.460    0.516    1.006        1.005
pixel centres     offset       -0.016    0.177    0.537        1.011
pixel centres     smoothed     -0.005    0.143    0.501        1.003
``cv2.ellipse``   traced       -0.072    0.271    0.944        1.055
``cv2.ellipse``   offset       +0.370    0.427    1.018        1.055
``cv2.ellipse``   smoothed     +0.381    0.422    0.954        1.044
================  ===========  ========  =======  ===========  ==========

("offset": the offset outline with its first filter, what ``find_components`` and the
default's tracker give; "smoothed": with six pairs of shrink-free passes as well, the
``reference`` preset's.)

The offset is kept: it removes the half-pixel shrinkage that would make every
contact about a pixel narrower than the finger. Mind the renderer, though: OpenCV's
filled shapes also colour pixels their boundary merely touches, which puts the edge
about 0.4 px further out on every side, so masks drawn with ``cv2.ellipse`` or
``cv2.fillPoly`` come out about 0.37 px fat after the offset. Sharp corners of tiny
blobs are rounded: a 3 × 3 pixel square's outline encloses 7.2 px², not 9.

**Component order.** Components are returned in raster order of their first pixel:
the component whose topmost row comes first, and of equal topmost rows the one whose
leftmost pixel on that row comes first. OpenCV returns them in the reverse of its scan,
so the order is made explicit rather than inherited.

**Limitation.** ``RETR_EXTERNAL`` reports only outermost boundaries: a component lying
entirely inside a hole of another one (a finger pressed inside a ring of touch) is not
reported, and holes do not reduce a component's area.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.contacts.resample import gather
from graspenv.geometry import Polylines, bounds_of
from graspenv.jit import njit

__all__ = [
    "Component",
    "Outlines",
    "components",
    "find_components",
    "find_components_batch",
    "find_outlines",
    "outline_from_chain",
    "outlines_from_chains",
    "traced_chains",
    "validate_mask",
]


def validate_mask(mask: object, shape: tuple[int, int] | None = None) -> NDArray[np.uint8]:
    """Check a contact mask and return it as a uint8 image OpenCV can read.

    Args:
        mask: contact image, shape (H, W), dtype bool or uint8; non-zero = touched.
            Pixel frame: row 0 at the top of the image.
        shape: the surface's mask shape (H, W); ``None`` accepts any 2-D shape.

    Returns:
        The same pixels as a C-contiguous uint8 array (a zero-copy view of a
        contiguous bool or uint8 mask; values are not rescaled, non-zero = touched).

    Raises:
        ValueError: ``mask`` is not a numpy array, is not 2-D, has a dtype other than
            bool or uint8, or its shape differs from ``shape``. The message names what
            was expected and what was given.
    """
    expected = f"an (H, W) = {shape} array" if shape is not None else "an (H, W) array"
    expected += " of dtype bool or uint8"
    if not isinstance(mask, np.ndarray):
        raise ValueError(f"mask must be a numpy ndarray, {expected}; got {type(mask).__name__}")
    if mask.ndim != 2:
        raise ValueError(f"mask must be {expected}; got {mask.ndim}-D array of shape {mask.shape}")
    if mask.dtype != np.bool_ and mask.dtype != np.uint8:
        raise ValueError(f"mask must be {expected}; got dtype {mask.dtype}")
    if shape is not None and mask.shape != tuple(shape):
        raise ValueError(f"mask must be {expected}; got shape {mask.shape}")
    image = np.ascontiguousarray(mask)
    if image.dtype == np.bool_:
        return image.view(np.uint8)
    return image


@dataclass(frozen=True, eq=False)
class Component:
    """One connected component of a mask, measured from its outer boundary.

    Attributes:
        chain: the traced boundary-pixel centres as OpenCV returns them, pixels
            (column, row), shape (K, 2), int32, in OpenCV's orientation:
            counter-clockwise as seen on the image, hence also in the world frame,
            though its shoelace area in raw (column, row) numbers is negative (rows go
            down). K = 1 for a single pixel; the chain doubles back along
            one-pixel-wide parts.
        outline: the chain moved outward onto the pixel footprint's edge and smoothed
            (module docstring), pixels (column, row), shape (L, 2), float64, L ≥ 3,
            same orientation, enclosing a positive area.
        area: number of pixels inside the outer boundary (holes included), pixels².
        centroid: centroid of the area enclosed by the traced chain, pixels
            (column, row), shape (2,); the mean of the chain where it encloses none.
    """

    chain: NDArray[np.int32]
    outline: NDArray[np.float64]
    area: float
    centroid: NDArray[np.float64]


def find_components(mask: NDArray[np.uint8], min_area: float = 0.0) -> list[Component]:
    """Components of a validated mask, in raster order of their first pixel.

    Args:
        mask: uint8 image, shape (H, W), non-zero = touched (see :func:`validate_mask`).
        min_area: components with fewer pixels than this are dropped.

    Returns:
        One :class:`Component` per 8-connected component that is not inside a hole of
        another, ordered by (topmost row, leftmost column on that row).
    """
    return find_components_batch(mask, min_area)[0]


def find_components_batch(
    mask: NDArray[np.uint8], min_area: float = 0.0
) -> tuple[list[Component], NDArray[np.float64], NDArray[np.intp]]:
    """:func:`find_components`, with the outlines also as one array.

    Returns:
        (components, outlines, bounds): the components; all their outlines one after
        another, pixels (column, row), shape (L, 2), of which each component's
        ``outline`` is a view; component i's is ``outlines[bounds[i]:bounds[i + 1]]``.
    """
    found = find_outlines(mask, min_area)
    outlines, bounds = found.outlines
    components = [
        Component(
            found.chains[found.chain_bounds[i] : found.chain_bounds[i + 1]],
            outlines[bounds[i] : bounds[i + 1]],
            float(found.areas[i]),
            found.centroids[i],
        )
        for i in range(len(found.areas))
    ]
    return components, outlines, bounds


class Outlines(NamedTuple):
    """Every component of a mask as arrays, in raster order of their first pixel (the
    per-frame form of :func:`find_components`: no object per component).

    Attributes:
        chains: the traced boundary chains one after another, pixels (column, row),
            int32, shape (K, 2); component i's is ``chains[chain_bounds[i]:
            chain_bounds[i + 1]]``.
        chain_bounds: shape (C + 1,).
        outlines: the outlines, pixels (column, row), one set per component.
        areas: pixels inside each outer boundary, shape (C,).
        centroids: pixels (column, row), shape (C, 2).
    """

    chains: NDArray[np.int32]
    chain_bounds: NDArray[np.intp]
    outlines: Polylines
    areas: NDArray[np.float64]
    centroids: NDArray[np.float64]


def find_outlines(mask: NDArray[np.uint8], min_area: float = 0.0, passes: int = 0) -> Outlines:
    """The components of a validated mask as arrays (:class:`Outlines`): one OpenCV
    call, then one compiled pass for areas, centroids, order and outlines.

    Args:
        mask: uint8 image, shape (H, W), non-zero = touched (see :func:`validate_mask`).
        min_area: components with fewer pixels than this are dropped.
        passes: pairs of shrink-free smoothing passes along each outline
            (``ContactConfig.outline_smoothing``), a whole number >= 0.

    Raises:
        ValueError: ``passes`` is not a whole number >= 0.
    """
    if not isinstance(passes, int | np.integer) or isinstance(passes, bool) or passes < 0:
        raise ValueError(f"passes must be a whole number >= 0, got {passes!r}")
    chains, chain_bounds = traced_chains(mask)
    return components(chains, chain_bounds, mask.shape[1], float(min_area), passes)


def traced_chains(mask: NDArray[np.uint8]) -> tuple[NDArray[np.int32], NDArray[np.intp]]:
    """Every outer boundary of a validated mask (one OpenCV call), laid end to end.

    Returns:
        (chains, bounds): boundary-pixel centres, pixels (column, row), int32, shape
        (K, 2), in OpenCV's order; chain i is ``chains[bounds[i]:bounds[i + 1]]``.
    """
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return np.zeros((0, 2), np.int32), np.zeros(1, np.intp)
    chains = np.concatenate(contours).reshape(-1, 2).astype(np.int32, copy=False)
    return chains, bounds_of([len(c) for c in contours])


@njit
def components(
    all_chains: NDArray[np.int32],
    all_bounds: NDArray[np.intp],
    width: int,
    min_area: float,
    passes: int = 0,
) -> Outlines:
    """:class:`Outlines` from traced chains (:func:`traced_chains`): areas and
    centroids, the components of at least ``min_area`` pixels in raster order of their
    first pixel, and their outlines, smoothed by ``passes`` more shrink-free pairs
    (``ContactConfig.outline_smoothing``)."""
    areas, centroids, keys = _measure_chains(all_chains, all_bounds, width)
    kept = np.flatnonzero(areas >= min_area)
    order = kept[np.argsort(keys[kept], kind="mergesort")]
    chains, chain_bounds = gather(all_chains, all_bounds, order)
    outlines, bounds = _outlines(chains.astype(np.float64), chain_bounds, passes)
    return Outlines(
        chains, chain_bounds, Polylines(outlines, bounds), areas[order], centroids[order]
    )


_CAP = 0.5  # half a pixel: the footprint edge beyond the centre of an end pixel
# Outlines with fewer points (blobs of a few pixels) are left as they are: their
# corners are real, not staircase.
_SMOOTH_FROM = 8


def outline_from_chain(chain: NDArray[np.integer]) -> NDArray[np.float64]:
    """Offset a traced boundary chain outward onto the pixel footprint's edge.

    Args:
        chain: boundary-pixel centres of one component, pixels (column, row), shape
            (K, 2), consecutive points 8-neighbours, closed (the last point joins the
            first), as ``cv2.findContours(..., CHAIN_APPROX_NONE)`` traces an outer
            border.

    Returns:
        The outline, pixels (column, row), shape (L, 2), same orientation as the
        chain; L = K plus one extra point per end where the chain doubles back, or 4
        for a single pixel. See the module docstring for the offset rule and its
        measured error.
    """
    points = np.asarray(chain).reshape(-1, 2)
    if len(points) == 0:
        return np.zeros((0, 2))
    outline, _ = outlines_from_chains([points])
    return outline


def outlines_from_chains(
    chains: Sequence[NDArray[np.integer]],
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """:func:`outline_from_chain` for many chains in one compiled pass.

    Args:
        chains: boundary chains, pixels (column, row), each of shape (K_i, 2) with
            K_i >= 1.

    Returns:
        (outlines, bounds): the outlines one after another, pixels (column, row),
        shape (L, 2), and outline i is ``outlines[bounds[i]:bounds[i + 1]]``,
        shape (len(chains) + 1,).
    """
    points = np.concatenate([np.asarray(c).reshape(-1, 2) for c in chains]).astype(np.float64)
    return _outlines(points, bounds_of([len(c) for c in chains]), 0)


@njit
def _measure_chains(
    chains: NDArray[np.int32], bounds: NDArray[np.intp], width: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Area, centroid and raster key of every chain (module docstring).

    The centroid is that of the polygon of boundary-pixel centres, with OpenCV's
    contour moments (``cv2.moments``) computed in the same order: exact sums of
    integers, scaled by ±1/2 and ±1/6. The key is the smallest ``row · width +
    column`` of the chain: Suzuki's outer border starts at the component's first
    pixel in raster order, but the minimum is taken so the order never depends on
    that detail.
    """
    count = len(bounds) - 1
    areas = np.empty(count)
    centroids = np.empty((count, 2))
    keys = np.empty(count, np.int64)
    for c in range(count):
        lo, hi = bounds[c], bounds[c + 1]
        size = hi - lo
        a00 = np.int64(0)
        a10 = np.int64(0)
        a01 = np.int64(0)
        x_before = np.int64(chains[hi - 1, 0])
        y_before = np.int64(chains[hi - 1, 1])
        key = np.int64(1) << 62
        sum_x = np.int64(0)
        sum_y = np.int64(0)
        for i in range(lo, hi):
            x = np.int64(chains[i, 0])
            y = np.int64(chains[i, 1])
            cross = x_before * y - x * y_before
            a00 += cross
            a10 += cross * (x_before + x)
            a01 += cross * (y_before + y)
            x_before, y_before = x, y
            key = min(key, y * width + x)
            sum_x += x
            sum_y += y
        keys[c] = key
        # Pick's theorem on the lattice polygon of boundary-pixel centres:
        # pixels = interior + boundary = enclosed + boundary / 2 + 1. It stays exact
        # where the chain doubles back (spurs, lines: enclosed = 0), because each
        # doubled-back pixel appears twice in the chain; a lone pixel appears once.
        if a00 != 0:
            half, sixth = (0.5, 1.0 / 6.0) if a00 > 0 else (-0.5, -1.0 / 6.0)
            enclosed = float(a00 * half)
            centroids[c, 0] = (a10 * sixth) / enclosed
            centroids[c, 1] = (a01 * sixth) / enclosed
        else:
            enclosed = 0.0
            centroids[c, 0] = sum_x / size
            centroids[c, 1] = sum_y / size
        areas[c] = enclosed + 0.5 * size + 1.0 if size > 1 else 1.0
    return areas, centroids, keys


@njit
def _outlines(
    points: NDArray[np.float64], bounds: NDArray[np.intp], passes: int
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """The outline of every chain (module docstring): offset half a pixel outward,
    capped where it doubles back, smoothed by [-1, 4, 10, 4, -1] / 16, then by
    ``passes`` pairs of Taubin's passes (:func:`_taubin`)."""
    count = len(bounds) - 1
    # Every point of a chain stays, and each end where it doubles back (a point
    # whose neighbours coincide) becomes the two corners of a cap; a single pixel
    # becomes its four corners.
    sizes = np.empty(count, np.intp)
    for c in range(count):
        lo, hi = bounds[c], bounds[c + 1]
        size = hi - lo
        if size == 1:
            sizes[c] = 4
            continue
        tips = 0
        for i in range(size):
            before = lo + (i - 1) % size
            after = lo + (i + 1) % size
            if points[before, 0] == points[after, 0] and points[before, 1] == points[after, 1]:
                tips += 1
        sizes[c] = size + tips
    out_bounds = np.zeros(count + 1, np.intp)
    out_bounds[1:] = np.cumsum(sizes)
    outlines = np.empty((out_bounds[-1], 2))
    fixed = np.zeros(out_bounds[-1], np.bool_)
    for c in range(count):
        lo, hi = out_bounds[c], out_bounds[c + 1]
        _outline_of(points[bounds[c] : bounds[c + 1]], outlines[lo:hi], fixed[lo:hi])
    smoothed = np.empty_like(outlines)
    for c in range(count):
        lo, hi = out_bounds[c], out_bounds[c + 1]
        size = hi - lo
        for i in range(lo, hi):
            if size < _SMOOTH_FROM or fixed[i]:
                smoothed[i, 0] = outlines[i, 0]
                smoothed[i, 1] = outlines[i, 1]
                continue
            k = i - lo
            b1, a1 = lo + (k - 1) % size, lo + (k + 1) % size
            b2, a2 = lo + (k - 2) % size, lo + (k + 2) % size
            for d in range(2):
                near = outlines[b1, d] + outlines[a1, d]
                far = outlines[b2, d] + outlines[a2, d]
                smoothed[i, d] = (10.0 * outlines[i, d] + 4.0 * near - far) / 16.0
    if passes > 0:
        _taubin(smoothed, out_bounds, fixed, passes)
    return smoothed, out_bounds


# Taubin's pair of passes (G. Taubin, "A signal processing approach to fair surface
# design", SIGGRAPH 1995): x += λ·Δx, then x += μ·Δx with μ < −λ, Δ the discrete
# Laplacian along the outline. The first shrinks, the second grows it back: a ripple
# of w points, for which Δ takes k = 1 − cos(2π/w), passes the pair scaled by
# (1 − λk)(1 − μk), unchanged below the pass band's k_PB = 1/λ + 1/μ ≈ 0.11 (w longer
# than about 13 points) and damped above it, the more the shorter (a ripple of 4
# points to a fifth over six pairs, of 2 points to nothing).
_TAUBIN_LAMBDA = 0.5
_TAUBIN_MU = -0.53
# Outlines with fewer points are left as the first filter made them: on a blob a few
# pixels across the whole outline is shorter than the pass band, and the pairs would
# round off its shape.
_TAUBIN_FROM = 16


@njit
def _taubin(
    outlines: NDArray[np.float64], bounds: NDArray[np.intp], fixed: NDArray[np.bool_], passes: int
) -> None:
    """Smooth every outline of at least :data:`_TAUBIN_FROM` points in place by
    ``passes`` pairs of Taubin's λ|μ passes; ``fixed`` rows (the corners of caps) stay."""
    source = np.empty_like(outlines)
    for step in range(2 * passes):
        factor = _TAUBIN_LAMBDA if step % 2 == 0 else _TAUBIN_MU
        source[:] = outlines
        for c in range(len(bounds) - 1):
            lo, hi = bounds[c], bounds[c + 1]
            size = hi - lo
            if size < _TAUBIN_FROM:
                continue
            for i in range(lo, hi):
                if fixed[i]:
                    continue
                k = i - lo
                before, after = lo + (k - 1) % size, lo + (k + 1) % size
                for d in range(2):
                    laplacian = 0.5 * (source[before, d] + source[after, d]) - source[i, d]
                    outlines[i, d] = source[i, d] + factor * laplacian


@njit
def _outline_of(
    chain: NDArray[np.float64], outline: NDArray[np.float64], fixed: NDArray[np.bool_]
) -> None:
    """One chain's offset outline (not yet smoothed) into ``outline``; ``fixed``, a
    flag per row of it, marks the corners of caps, which smoothing must keep."""
    size = len(chain)
    if size == 1:
        corners = ((-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0))
        for k in range(4):
            outline[k, 0] = chain[0, 0] + _CAP * corners[k][0]
            outline[k, 1] = chain[0, 1] + _CAP * corners[k][1]
        return
    # OpenCV's outer borders have a negative shoelace area in (column, row), for
    # which (-dy, dx) of the tangent points out of the shape. Check rather than
    # trust it; a chain enclosing nothing has no inside, and either side will do.
    cross = 0.0
    for i in range(size):
        j = (i + 1) % size
        cross += chain[i, 0] * chain[j, 1] - chain[i, 1] * chain[j, 0]
    outward = 1.0 if cross <= 0.0 else -1.0
    out = 0
    for here in range(size):
        before = (here - 1) % size
        after = (here + 1) % size
        tx = chain[after, 0] - chain[before, 0]
        ty = chain[after, 1] - chain[before, 1]
        length = np.hypot(tx, ty)
        if length == 0.0:
            # The chain doubles back here (the end of a line or spur): two corners
            # of a square cap, first on the side it arrives along, then on the side
            # it leaves along.
            ax = chain[here, 0] - chain[before, 0]
            ay = chain[here, 1] - chain[before, 1]
            norm = np.hypot(ax, ay)
            ax /= norm
            ay /= norm
            sx, sy = -outward * ay, outward * ax
            outline[out, 0] = chain[here, 0] + _CAP * (ax + sx)
            outline[out, 1] = chain[here, 1] + _CAP * (ay + sy)
            outline[out + 1, 0] = chain[here, 0] + _CAP * (ax - sx)
            outline[out + 1, 1] = chain[here, 1] + _CAP * (ay - sy)
            fixed[out] = True
            fixed[out + 1] = True
            out += 2
            continue
        # Half a pixel along the dominant axis of the outward normal n.
        nx = -outward * ty / length
        ny = outward * tx / length
        offset = 0.5 * max(abs(nx), abs(ny))
        outline[out, 0] = chain[here, 0] + offset * nx
        outline[out, 1] = chain[here, 1] + offset * ny
        out += 1
