"""Connected components of a contact mask and their outer outlines, in pixels.

One pass of OpenCV's border following (``cv2.findContours`` with ``RETR_EXTERNAL``
and ``CHAIN_APPROX_NONE``) gives every component's outer boundary; ``cv2.moments`` of
that boundary gives its area and centroid. This is far cheaper than labelling the
image (``connectedComponentsWithStats``) and is what the tracker runs every frame.

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
without shrinking curves.

Measured against the analytic boundary of 400 random ellipses with 6.3-12.6 px
semi-axes (6-12 mm fingertips on the default table): signed distance of outline
vertices and edge midpoints in pixels, and outline length over the true perimeter
(``python -m tests.contacts.measure_outline``):

================  ===========  ========  =======  ===========  ==========
mask rendered by  outline      mean      RMS      largest |.|  length
================  ===========  ========  =======  ===========  ==========
pixel centres     traced       -0.460    0.516    1.006        1.005
pixel centres     this module  -0.016    0.177    0.537        1.011
``cv2.ellipse``   traced       -0.072    0.271    0.944        1.055
``cv2.ellipse``   this module  +0.370    0.427    1.018        1.055
================  ===========  ========  =======  ===========  ==========

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

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.contacts.resample import bounds_of

__all__ = [
    "Component",
    "find_components",
    "find_components_batch",
    "outline_from_chain",
    "outlines_from_chains",
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
    """:func:`find_components`, with the outlines also as one array (the per-frame path:
    the next stages take every outline of the frame at once).

    Returns:
        (components, outlines, bounds): the components; all their outlines one after
        another, pixels (column, row), shape (L, 2), of which each component's
        ``outline`` is a view; component i's is ``outlines[bounds[i]:bounds[i + 1]]``.
    """
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    found: list[tuple[int, NDArray[np.int32], float, NDArray[np.float64]]] = []
    for contour in contours:
        chain = np.asarray(contour, dtype=np.int32).reshape(-1, 2)
        moments = cv2.moments(contour)
        enclosed = abs(moments["m00"])
        # Pick's theorem on the lattice polygon of boundary-pixel centres:
        # pixels = interior + boundary = enclosed + boundary / 2 + 1. It stays exact
        # where the chain doubles back (spurs, lines: enclosed = 0), because each
        # doubled-back pixel appears twice in the chain; a lone pixel appears once.
        area = enclosed + 0.5 * len(chain) + 1.0 if len(chain) > 1 else 1.0
        if area < min_area:
            continue
        if enclosed > 0.0:
            centroid = np.array([moments["m10"], moments["m01"]]) / moments["m00"]
        else:
            centroid = chain.mean(axis=0, dtype=np.float64)
        # Suzuki's outer border starts at the component's first pixel in raster order,
        # but take the minimum explicitly so the order never depends on that detail.
        key = int((chain[:, 1].astype(np.int64) * mask.shape[1] + chain[:, 0]).min())
        found.append((key, chain, float(area), centroid))
    if not found:
        return [], np.zeros((0, 2)), np.zeros(1, dtype=np.intp)
    found.sort(key=lambda item: item[0])
    outlines, bounds = outlines_from_chains([chain for _, chain, _, _ in found])
    components = [
        Component(chain, outlines[bounds[i] : bounds[i + 1]], area, centroid)
        for i, (_, chain, area, centroid) in enumerate(found)
    ]
    return components, outlines, bounds


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
    """:func:`outline_from_chain` for many chains in one pass.

    Chains that never double back (fingertips, palms: the per-frame case) go through
    one fixed sequence of numpy calls together; a chain with a line or spur, or a
    single pixel, is capped on its own.

    Args:
        chains: boundary chains, pixels (column, row), each of shape (K_i, 2) with
            K_i >= 1.

    Returns:
        (outlines, bounds): the outlines one after another, pixels (column, row),
        shape (L, 2), and outline i is ``outlines[bounds[i]:bounds[i + 1]]``,
        shape (len(chains) + 1,).
    """
    sizes = np.array([len(c) for c in chains], dtype=np.intp)
    bounds = bounds_of(sizes)
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
        return np.concatenate(pieces), bounds_of([len(p) for p in pieces])
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
