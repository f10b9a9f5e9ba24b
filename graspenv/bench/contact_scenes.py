"""Synthetic fingertips for the contact tests and measurements: analytic ellipses,
their rasterised masks and their contours under realistic finger motion."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.contacts.extract import find_components
from graspenv.contacts.resample import orient_ccw, resample_closed
from graspenv.surface.geometry import Surface

#: How :func:`ellipse_mask` can fill an ellipse.
RASTERISERS = ("centres", "cv2.ellipse")


def ellipse_mask(
    shape: tuple[int, int],
    centre_px: NDArray[np.float64],
    axes_px: tuple[float, float],
    angle: float,
    rasteriser: str = "centres",
) -> NDArray[np.uint8]:
    """A filled ellipse as a 0/1 mask.

    Args:
        shape: mask (H, W).
        centre_px: pixels (column, row), shape (2,).
        axes_px: semi-axes, pixels.
        angle: rotation of the first axis from the column axis, radians (towards rows).
        rasteriser: ``"centres"``: the pixels whose centres lie inside (exact
            pixel-centre sampling); ``"cv2.ellipse"``: filled by OpenCV with 8
            fractional bits.
    """
    if rasteriser == "cv2.ellipse":
        mask = np.zeros(shape, np.uint8)
        scale = 256.0
        cv2.ellipse(
            mask,
            (round(centre_px[0] * scale), round(centre_px[1] * scale)),
            (round(axes_px[0] * scale), round(axes_px[1] * scale)),
            float(np.degrees(angle)),
            0.0,
            360.0,
            1,
            thickness=-1,
            lineType=cv2.LINE_8,
            shift=8,
        )
        return mask
    if rasteriser != "centres":
        raise ValueError(f"rasteriser must be one of {RASTERISERS}, got {rasteriser!r}")
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    dx = cols - centre_px[0]
    dy = rows - centre_px[1]
    c, s = np.cos(angle), np.sin(angle)
    u = (c * dx + s * dy) / axes_px[0]
    v = (-s * dx + c * dy) / axes_px[1]
    return (u * u + v * v <= 1.0).astype(np.uint8)


def ellipse_signed_distance(
    points_px: NDArray[np.float64],
    centre_px: NDArray[np.float64],
    axes_px: tuple[float, float],
    angle: float,
) -> NDArray[np.float64]:
    """Distance of points to an ellipse boundary, negative inside (any unit; pixels
    here). The closest boundary parameter is bracketed on 256 samples and polished by
    Newton's method, so the distance is exact to ~1e-9 of the axes."""
    c, s = np.cos(angle), np.sin(angle)
    dx = np.asarray(points_px, dtype=float)[:, 0] - centre_px[0]
    dy = np.asarray(points_px, dtype=float)[:, 1] - centre_px[1]
    x = c * dx + s * dy
    y = -s * dx + c * dy
    a, b = axes_px
    t = np.linspace(0.0, 2.0 * np.pi, 256, endpoint=False)
    coarse = (a * np.cos(t)[None, :] - x[:, None]) ** 2 + (b * np.sin(t)[None, :] - y[:, None]) ** 2
    theta = t[np.argmin(coarse, axis=1)]
    for _ in range(8):
        # d/dθ of half the squared distance, and its derivative.
        g = (b * b - a * a) * np.sin(theta) * np.cos(theta) + a * x * np.sin(theta)
        g -= b * y * np.cos(theta)
        h = (b * b - a * a) * np.cos(2.0 * theta) + a * x * np.cos(theta) + b * y * np.sin(theta)
        theta = theta - g / np.where(np.abs(h) > 1e-12, h, 1e-12)
    d = np.hypot(a * np.cos(theta) - x, b * np.sin(theta) - y)
    inside = (x / a) ** 2 + (y / b) ** 2 < 1.0
    return np.where(inside, -d, d)


def random_fingertip(
    rng: np.random.Generator, surface: Surface, margin: float = 0.05
) -> tuple[NDArray[np.float64], tuple[float, float], float]:
    """A fingertip ellipse: centre (metres, world), semi-axes 6-12 mm, angle (rad)."""
    half = 0.5 * np.asarray(surface.size) - margin
    centre = rng.uniform(-half, half)
    axes = (float(rng.uniform(0.006, 0.012)), float(rng.uniform(0.006, 0.012)))
    return centre, axes, float(rng.uniform(0.0, np.pi))


def ellipse_mask_world(
    surface: Surface, centre: NDArray[np.float64], axes: tuple[float, float], angle: float
) -> NDArray[np.bool_]:
    """Pixels whose centres lie inside a world-frame ellipse (pixel-centre sampling).

    Args:
        surface: the table.
        centre: metres, world frame, shape (2,).
        axes: semi-axes, metres.
        angle: rotation of the first axis from world x, radians, counter-clockwise.
    """
    h, w = surface.shape
    rows, cols = np.mgrid[0:h, 0:w]
    xy = surface.pixel_to_world(np.stack([cols, rows], axis=-1))
    d = xy - centre
    c, s = np.cos(angle), np.sin(angle)
    u = (c * d[..., 0] + s * d[..., 1]) / axes[0]
    v = (-s * d[..., 0] + c * d[..., 1]) / axes[1]
    return np.asarray(u * u + v * v <= 1.0)


Finger = tuple[NDArray[np.float64], tuple[float, float], float]
"""A fingertip ellipse: centre (metres, world frame, (2,)), semi-axes (m), angle (rad,
counter-clockwise from world x)."""


def render_fingers(surface: Surface, fingers: list[Finger]) -> NDArray[np.bool_]:
    """A contact mask of fingertip ellipses, by pixel-centre sampling; each ellipse is
    evaluated only over its bounding box, so a full-table mask stays cheap."""
    mask = np.zeros(surface.shape, dtype=bool)
    h, w = surface.shape
    for centre, axes, angle in fingers:
        reach = max(axes)
        corners = surface.world_to_pixel(
            np.array([centre - reach, centre + reach], dtype=np.float64)
        )
        c0, c1 = np.sort(corners[:, 0])
        r0, r1 = np.sort(corners[:, 1])
        c0, r0 = max(int(np.floor(c0)) - 1, 0), max(int(np.floor(r0)) - 1, 0)
        c1, r1 = min(int(np.ceil(c1)) + 2, w), min(int(np.ceil(r1)) + 2, h)
        if c0 >= c1 or r0 >= r1:
            continue
        rows, cols = np.mgrid[r0:r1, c0:c1]
        d = surface.pixel_to_world(np.stack([cols, rows], axis=-1)) - centre
        c, s = np.cos(angle), np.sin(angle)
        u = (c * d[..., 0] + s * d[..., 1]) / axes[0]
        v = (-s * d[..., 0] + c * d[..., 1]) / axes[1]
        mask[r0:r1, c0:c1] |= u * u + v * v <= 1.0
    return mask


def world_ellipse_distance(points: NDArray[np.float64], finger: Finger) -> NDArray[np.float64]:
    """Distance of world points (metres, (N, 2)) to a finger's ellipse boundary,
    metres, negative inside."""
    centre, axes, angle = finger
    c, s = np.cos(angle), np.sin(angle)
    d = points - centre
    local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)
    return ellipse_signed_distance(local, np.zeros(2), axes, 0.0)


def lobed_mask_world(
    surface: Surface,
    centre: NDArray[np.float64],
    radius: float,
    angle: float,
    lobes: int = 5,
    depth: float = 0.15,
) -> NDArray[np.bool_]:
    """Pixels whose centres lie inside r(θ) = radius·(1 + depth·sin(lobes·(θ - angle))),
    a hand-sized outline with fingers for the 512-point cases; world frame, metres."""
    h, w = surface.shape
    rows, cols = np.mgrid[0:h, 0:w]
    d = surface.pixel_to_world(np.stack([cols, rows], axis=-1)) - centre
    theta = np.arctan2(d[..., 1], d[..., 0])
    limit = radius * (1.0 + depth * np.sin(lobes * (theta - angle)))
    return np.asarray(np.hypot(d[..., 0], d[..., 1]) <= limit)


# A patch of the default table (same ~0.955 mm pixels) big enough for one fingertip
# and a frame of its motion; rendering it is much cheaper than the whole table.
FINGER_PATCH = Surface(size=(0.061, 0.046), resolution=(64, 48))
HAND_PATCH = Surface(size=(0.2135, 0.2013), resolution=(224, 210))
DT = 1.0 / 60.0


def _world_contour(
    surface: Surface, mask: NDArray[np.bool_], spacing: float, rng: np.random.Generator
) -> NDArray[np.float64]:
    """The largest component's outline in the world frame, counter-clockwise, resampled
    from a random point of the outline (where the tracer starts is arbitrary)."""
    components = find_components(mask.view(np.uint8))
    component = max(components, key=lambda c: c.area)
    outline = orient_ccw(surface.pixel_to_world(component.outline))
    start = outline[rng.integers(len(outline))]
    return resample_closed(outline, spacing, start)


def fingertip_motion(
    rng: np.random.Generator,
    speed_max: float = 0.5,
    turn_max: float = 3.0,
    spacing: tuple[float, float] = (0.002, 0.004),
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Previous and current contour of a fingertip over one 60 Hz frame.

    Fingertip ellipse with 6-12 mm semi-axes; speed uniform up to ``speed_max`` m/s in
    a random direction; turn rate uniform within ±``turn_max`` rad/s; semi-axes
    changing by ~2 % (pressure), so the point counts differ; spacing uniform in the
    given range, metres. Returns (P, Q), metres, world frame, counter-clockwise.
    """
    step = float(rng.uniform(*spacing))
    axes = rng.uniform(0.006, 0.012, size=2)
    angle = float(rng.uniform(0.0, np.pi))
    heading = float(rng.uniform(0.0, 2.0 * np.pi))
    velocity = float(rng.uniform(0.0, speed_max)) * np.array([np.cos(heading), np.sin(heading)])
    centre = -0.5 * velocity * DT + rng.uniform(-0.5, 0.5, size=2) * FINGER_PATCH.pixel_size
    turn = float(rng.uniform(-turn_max, turn_max)) * DT
    axes_next = axes * (1.0 + rng.normal(0.0, 0.02, size=2))
    before = ellipse_mask_world(FINGER_PATCH, centre, (axes[0], axes[1]), angle)
    after = ellipse_mask_world(
        FINGER_PATCH, centre + velocity * DT, (axes_next[0], axes_next[1]), angle + turn
    )
    return (
        _world_contour(FINGER_PATCH, before, step, rng),
        _world_contour(FINGER_PATCH, after, step, rng),
    )


def hand_motion(
    rng: np.random.Generator, points: int = 512, speed_max: float = 0.5, turn_max: float = 3.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Previous and current contour of a lobed hand-sized blob resampled to about
    ``points`` points (spacing set from its perimeter), over one 60 Hz frame."""
    radius = float(rng.uniform(0.07, 0.08))
    angle = float(rng.uniform(0.0, 2.0 * np.pi))
    heading = float(rng.uniform(0.0, 2.0 * np.pi))
    velocity = float(rng.uniform(0.0, speed_max)) * np.array([np.cos(heading), np.sin(heading)])
    centre = -0.5 * velocity * DT
    turn = float(rng.uniform(-turn_max, turn_max)) * DT
    before = lobed_mask_world(HAND_PATCH, centre, radius, angle)
    after = lobed_mask_world(
        HAND_PATCH, centre + velocity * DT, radius * (1.0 + rng.normal(0.0, 0.01)), angle + turn
    )
    components = find_components(before.view(np.uint8))
    outline = orient_ccw(HAND_PATCH.pixel_to_world(components[0].outline))
    perimeter = float(np.sum(np.linalg.norm(np.roll(outline, -1, 0) - outline, axis=1)))
    step = perimeter / points
    return (
        _world_contour(HAND_PATCH, before, step, rng),
        _world_contour(HAND_PATCH, after, step, rng),
    )
