"""Image-space sensing of the instant-proxy baseline: edge pixels and image motion."""

from __future__ import annotations

import cv2
import numpy as np

from graspenv.contacts.edges import backward_flow, edge_pixels


def _blobs(shift: int = 0) -> np.ndarray:
    mask = np.zeros((480, 640), np.uint8)
    cv2.circle(mask, (300 + shift, 240), 12, 1, -1)
    cv2.ellipse(mask, (380 + shift, 250), (15, 9), 30.0, 0, 360, 1, -1)
    return mask


def _full_image_edges(mask: np.ndarray) -> np.ndarray:
    """The definition on the whole image (the slow, sure way)."""
    image = np.where(mask != 0, 255.0, 0.0).astype(np.float32)
    magnitude = np.hypot(cv2.Sobel(image, cv2.CV_32F, 1, 0), cv2.Sobel(image, cv2.CV_32F, 0, 1))
    rows, cols = np.nonzero((magnitude >= 0.5 * 4 * 255.0) & (mask != 0))
    return np.column_stack([cols, rows]).astype(float)


def test_edge_pixels_are_the_whole_images_in_raster_order() -> None:
    mask = _blobs()
    mask[0, 5] = mask[479, 639] = 1  # touched pixels on the image border too
    expected = _full_image_edges(mask)
    np.testing.assert_array_equal(edge_pixels(mask), expected)
    np.testing.assert_array_equal(edge_pixels(mask, stride=3), expected[::3])
    assert edge_pixels(np.zeros((48, 64), np.uint8)).shape == (0, 2)


def test_backward_flow_finds_where_the_edge_pixels_were() -> None:
    before, now = _blobs(), _blobs(shift=3)
    pixels = edge_pixels(now)
    was = backward_flow(before, now, pixels)
    assert was.shape == pixels.shape
    # The blobs moved 3 px along +x: each edge pixel came from about 3 px to the left.
    np.testing.assert_allclose(np.median(was - pixels, axis=0), [-3.0, 0.0], atol=0.5)
    assert backward_flow(before, now, np.zeros((0, 2))).shape == (0, 2)
