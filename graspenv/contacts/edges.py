"""Image-space sensing for the instant-proxy baseline (Wilson et al., UIST 2008):
strong-gradient pixels of the mask and the image motion between two masks."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["backward_flow", "edge_pixels"]

# Half of the Sobel 3×3 response of a clean 0/255 step edge: a pixel on either side
# of every boundary passes, flat regions never do.
_EDGE_THRESHOLD = 0.5 * 4 * 255.0


def edge_pixels(mask: NDArray[np.uint8], stride: int = 1) -> NDArray[np.float64]:
    """Pixels of strong mask gradient, on the touched side of each boundary.

    Args:
        mask: (H, W) uint8, non-zero = touched.
        stride: keep every ``stride``-th edge pixel in raster order (1 keeps all).

    Returns:
        pixels (column, row), shape (N, 2), in raster order.
    """
    # Only the touched pixels' 3 × 3 neighbourhoods matter: the Sobel image of the
    # touched region with a two-pixel border is the full image's there, exactly.
    window = _touched_window(mask, 2)
    if window is None:
        return np.zeros((0, 2))
    x0, y0, x1, y1 = window
    crop = mask[y0:y1, x0:x1]
    image = np.where(crop != 0, 255.0, 0.0).astype(np.float32)
    gx = cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(image, cv2.CV_32F, 0, 1, ksize=3)
    strong = (np.hypot(gx, gy) >= _EDGE_THRESHOLD) & (crop != 0)
    rows, cols = np.nonzero(strong)
    return np.column_stack([cols + x0, rows + y0]).astype(float)[::stride]


# The flow is computed on the touched region of both masks and this many pixels
# around it (about the reach of Farneback's 15-pixel window on the second pyramid
# level), its corner on a multiple of _FLOW_ALIGN so that the pyramid's pixel grid is
# the full image's. On the two-finger turn and slide this is 12 times faster than
# the flow of the whole 640 × 480 image and moves no particle by more than 1e-5 px.
_FLOW_MARGIN = 48
_FLOW_ALIGN = 8


def _touched_window(
    mask: NDArray[np.uint8], margin: int, align: int = 1
) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1): the bounding box of the non-zero pixels grown by ``margin``,
    its corner rounded down to a multiple of ``align``, clipped to the image; None
    when nothing is touched."""
    points = cv2.findNonZero(mask)
    if points is None:
        return None
    x, y, w, h = cv2.boundingRect(points)
    height, width = mask.shape
    x0 = max(x - margin, 0) // align * align
    y0 = max(y - margin, 0) // align * align
    return x0, y0, min(x + w + margin, width), min(y + h + margin, height)


def backward_flow(
    previous: NDArray[np.uint8], current: NDArray[np.uint8], pixels: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Where the given pixels of ``current`` were in ``previous`` (dense optical flow).

    Farneback's flow on blurred masks: a binary mask has no texture inside blobs,
    so only the motion of their edges is seen, which is where the particles are.

    Args:
        previous: (H, W) uint8 mask of the last frame.
        current: (H, W) uint8 mask of this frame.
        pixels: pixels (column, row) of the current frame, shape (N, 2).

    Returns:
        pixels (column, row) in the previous frame, shape (N, 2).
    """
    if len(pixels) == 0:
        return pixels.copy()
    either: NDArray[np.uint8] = np.bitwise_or(previous, current)
    window = _touched_window(either, _FLOW_MARGIN, _FLOW_ALIGN)
    assert window is not None  # the pixels are touched pixels of ``current``
    x0, y0, x1, y1 = window
    a = np.where(current[y0:y1, x0:x1] != 0, 255, 0).astype(np.uint8)
    b = np.where(previous[y0:y1, x0:x1] != 0, 255, 0).astype(np.uint8)
    blurred_a = cv2.GaussianBlur(a, (0, 0), 2.0)
    blurred_b = cv2.GaussianBlur(b, (0, 0), 2.0)
    flow = np.zeros((*a.shape, 2), np.float32)
    flow = cv2.calcOpticalFlowFarneback(blurred_a, blurred_b, flow, 0.5, 3, 15, 3, 5, 1.2, 0)
    idx = np.round(pixels).astype(int)
    return pixels + flow[idx[:, 1] - y0, idx[:, 0] - x0].astype(float)
