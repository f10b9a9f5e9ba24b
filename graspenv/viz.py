"""Pictures: frames of the table with mask, contours, particles and objects.

Picture making is one of the two places (with the sensing stages) where OpenCV is
used. Images are BGR ``uint8`` arrays of shape (H, W, 3), as OpenCV writes them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.surface.geometry import Surface

__all__ = [
    "BACKGROUND",
    "contact_sheet",
    "draw_mask",
    "draw_points",
    "draw_polyline",
    "id_colour",
    "put_label",
    "write_animation",
]

Image = NDArray[np.uint8]

BACKGROUND = (40, 34, 30)
MASK_COLOUR = (120, 120, 120)
_SUBPIXEL_BITS = 4

# A qualitative palette (BGR) so neighbouring contact ids are easy to tell apart.
_PALETTE = (
    (75, 180, 60),
    (48, 130, 245),
    (230, 50, 240),
    (60, 245, 210),
    (200, 130, 0),
    (25, 225, 255),
    (180, 30, 145),
    (240, 240, 70),
    (0, 0, 230),
    (128, 128, 0),
)


def id_colour(contact_id: int) -> tuple[int, int, int]:
    """A stable BGR colour for a contact id."""
    return _PALETTE[contact_id % len(_PALETTE)]


def draw_mask(mask: NDArray[np.generic], scale: int = 1) -> Image:
    """A BGR canvas with touched pixels in grey.

    Args:
        mask: (H, W) bool or uint8, non-zero = touched.
        scale: integer upscaling of the picture (pixels per camera pixel).
    """
    canvas = np.empty((*mask.shape, 3), np.uint8)
    canvas[:] = BACKGROUND
    canvas[np.asarray(mask) != 0] = MASK_COLOUR
    if scale != 1:
        canvas = cv2.resize(canvas, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    return canvas


def _to_canvas(surface: Surface, xy: NDArray[np.float64], scale: float) -> NDArray[np.int32]:
    # Pixel centres sit at integer coordinates; the canvas pixel (c, r) of a scaled
    # picture covers camera pixels [c/scale - 0.5, ...], hence the half-pixel shift.
    px = (surface.world_to_pixel(xy) + 0.5) * scale - 0.5
    return np.round(px * (1 << _SUBPIXEL_BITS)).astype(np.int32)


def draw_polyline(
    canvas: Image,
    surface: Surface,
    xy: NDArray[np.float64],
    colour: tuple[int, int, int],
    scale: float = 1.0,
    closed: bool = True,
    thickness: int = 1,
) -> None:
    """Draw a world polyline (metres, world frame, shape (N, 2)) onto a canvas."""
    if len(xy) == 0:
        return
    pts = _to_canvas(surface, np.asarray(xy, float), scale)
    cv2.polylines(canvas, [pts], closed, colour, thickness, cv2.LINE_AA, _SUBPIXEL_BITS)


def draw_points(
    canvas: Image,
    surface: Surface,
    xy: NDArray[np.float64],
    colours: tuple[int, int, int] | Sequence[tuple[int, int, int]],
    scale: float = 1.0,
    radius: float = 1.5,
) -> None:
    """Draw world points (metres, world frame, shape (N, 2)) as filled dots.

    Args:
        colours: one BGR colour for all points, or one per point.
        radius: dot radius in canvas pixels.
    """
    pts = _to_canvas(surface, np.asarray(xy, float).reshape(-1, 2), scale)
    r = round(radius * (1 << _SUBPIXEL_BITS))
    palette = np.broadcast_to(np.asarray(colours, dtype=int).reshape(-1, 3), (len(pts), 3))
    for (x, y), (b, g, red) in zip(pts, palette, strict=True):
        colour = (int(b), int(g), int(red))
        cv2.circle(canvas, (int(x), int(y)), r, colour, -1, cv2.LINE_AA, _SUBPIXEL_BITS)


def put_label(
    canvas: Image, text: str, row: int = 0, colour: tuple[int, int, int] = (230, 230, 230)
) -> None:
    """Write a line of text at the top left of a canvas (row 0 is the first line)."""
    y = 18 + 18 * row
    cv2.putText(canvas, text, (8, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.putText(canvas, text, (8, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, colour, 1, cv2.LINE_AA)


def contact_sheet(images: Sequence[Image], columns: int, gap: int = 4) -> Image:
    """Tile equally sized images into one picture, row by row."""
    if not images:
        raise ValueError("contact_sheet needs at least one image")
    h, w = images[0].shape[:2]
    rows = -(-len(images) // columns)
    sheet = np.full(
        (rows * h + (rows - 1) * gap, columns * w + (columns - 1) * gap, 3), 255, np.uint8
    )
    for i, image in enumerate(images):
        r, c = divmod(i, columns)
        sheet[r * (h + gap) : r * (h + gap) + h, c * (w + gap) : c * (w + gap) + w] = image
    return sheet


def write_animation(frames: Iterable[Image], path: str | Path, fps: float) -> Path:
    """Write frames as an animated GIF (``.gif``) or an MP4 video (``.mp4``).

    Returns:
        the path written.

    Raises:
        ValueError: no frames, or an unsupported suffix.
        OSError: OpenCV could not write the file.
    """
    path = Path(path)
    frames = list(frames)
    if not frames:
        raise ValueError("write_animation needs at least one frame")
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".gif":
        animation = cv2.Animation()
        animation.frames = frames
        animation.durations = [round(1000.0 / fps)] * len(frames)
        ok = cv2.imwriteanimation(str(path), animation)
    elif path.suffix == ".mp4":
        h, w = frames[0].shape[:2]
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), fps, (w, h))
        ok = writer.isOpened()
        for frame in frames:
            writer.write(frame)
        writer.release()
    else:
        raise ValueError(f"write_animation: expected a .gif or .mp4 path, got {path}")
    if not ok:
        raise OSError(f"OpenCV could not write {path}")
    return path
