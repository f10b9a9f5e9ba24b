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
    image = np.where(mask != 0, 255.0, 0.0).astype(np.float32)
    gx = cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(image, cv2.CV_32F, 0, 1, ksize=3)
    strong = (np.hypot(gx, gy) >= _EDGE_THRESHOLD) & (mask != 0)
    rows, cols = np.nonzero(strong)
    return np.column_stack([cols, rows]).astype(float)[::stride]


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
    a = cv2.GaussianBlur(np.where(current != 0, 255, 0).astype(np.uint8), (0, 0), 2.0)
    b = cv2.GaussianBlur(np.where(previous != 0, 255, 0).astype(np.uint8), (0, 0), 2.0)
    flow = np.zeros((*a.shape, 2), np.float32)
    flow = cv2.calcOpticalFlowFarneback(a, b, flow, 0.5, 3, 15, 3, 5, 1.2, 0)
    idx = np.round(pixels).astype(int)
    return pixels + flow[idx[:, 1], idx[:, 0]].astype(float)
