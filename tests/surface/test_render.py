"""Mask rendering: sub-pixel accuracy against the analytic shapes, ground-truth motion
against finite differences of renders, touch flags and the union of shapes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from graspenv.surface import (
    ContactShape,
    Fingertip,
    Hand,
    HandEdge,
    Palm,
    PolygonShape,
    SensorNoise,
    Surface,
    Thumb,
    render_coverage,
    render_mask,
)

# A pixel centre this far (in pixels) inside a shape must be set, this far outside
# unset. Measured worst cases: 0.2 px for curved edges, 0.4 px at a card's corners.
TOLERANCE_PX = 0.6


def _contour_pixels(mask: NDArray[np.uint8]) -> NDArray[np.float64]:
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    assert len(contours) == 1
    return contours[0].reshape(-1, 2).astype(float)


def _polyline_distance(points: NDArray[np.float64], chain: NDArray[np.float64]) -> NDArray:
    a = chain[None, :, :]
    edge = np.roll(chain, -1, axis=0)[None, :, :] - a
    rel = points[:, None, :] - a
    t = np.clip(np.sum(rel * edge, axis=2) / np.maximum(np.sum(edge * edge, axis=2), 1e-12), 0, 1)
    gap = rel - t[..., None] * edge
    return np.hypot(gap[..., 0], gap[..., 1]).min(axis=1)


def _misclassified(
    shape: ContactShape, surface: Surface, pixel_centres: NDArray, pixel: float
) -> tuple[float, float]:
    """Deepest set pixel outside and deepest unset pixel inside the shape, in pixels."""
    mask = render_mask(shape, surface).ravel() > 0
    near = np.all(np.abs(pixel_centres - shape.centre) <= shape.bounding_radius + 4 * pixel, 1)
    distance = shape.signed_distance(pixel_centres[near]) / pixel
    touched = mask[near]
    outside = float(distance[touched].max(initial=-np.inf))
    inside = float(-distance[~touched].min(initial=np.inf))
    assert not mask[~near].any()
    return outside, inside


positions = st.tuples(st.floats(-0.25, 0.25), st.floats(-0.18, 0.18))
angles = st.floats(0.0, 2 * np.pi)
lengths = st.floats(0.004, 0.05)

SHAPES = {
    "fingertip": st.builds(
        lambda c, a, r1, r2, p: Fingertip(c, a, radii=(r1, r2), press=p),
        positions,
        angles,
        st.floats(0.003, 0.015),
        st.floats(0.003, 0.015),
        st.floats(0.0, 1.0),
    ),
    "palm": st.builds(
        lambda c, a, w, h, f: Palm(c, a, size=(w, h), corner_radius=f * min(w, h) / 2),
        positions,
        angles,
        lengths,
        lengths,
        st.floats(0.0, 1.0),
    ),
    # Narrower than about 1.5 px, a shape is not reliably drawn; hand edges are wider.
    "hand edge": st.builds(
        lambda c, a, long, f: HandEdge(c, a, length=long, width=0.003 + f * (long - 0.003)),
        positions,
        angles,
        st.floats(0.003, 0.1),
        st.floats(0.0, 1.0),
    ),
    "card": st.builds(
        lambda c, a, w, h: PolygonShape.rectangle((w, h), c, a), positions, angles, lengths, lengths
    ),
}


@pytest.mark.parametrize("kind", SHAPES)
@settings(deadline=None, max_examples=25)
@given(data=st.data())
def test_pixels_far_from_the_edge_are_classified_right(
    kind: str,
    data: st.DataObject,
    surface: Surface,
    pixel_centres: NDArray,
    pixel: float,
) -> None:
    shape = data.draw(SHAPES[kind])
    outside, inside = _misclassified(shape, surface, pixel_centres, pixel)
    assert outside <= TOLERANCE_PX
    assert inside <= TOLERANCE_PX


def test_rendering_is_unbiased_on_average(surface: Surface) -> None:
    # Thresholding OpenCV's anti-aliased fill at one half would grow every edge by
    # about 0.7 px; the inset must cancel that, not just hide it in the tolerance.
    rng = np.random.default_rng(11)
    pixel_area = float(np.prod(surface.pixel_size))
    offsets = []
    for _ in range(40):
        tip = Fingertip(rng.uniform(-0.2, 0.2, 2), rng.uniform(0, 6), rng.uniform(0.004, 0.012, 2))
        count = np.count_nonzero(render_mask(tip, surface))
        perimeter = tip.outline(1e-4)
        length = np.hypot(*(np.roll(perimeter, -1, axis=0) - perimeter).T).sum()
        offsets.append((count - tip.area / pixel_area) / (length / surface.pixel_size.mean()))
    assert abs(float(np.mean(offsets))) < 0.1


def test_ellipse_contour_hugs_the_analytic_ellipse(surface: Surface, pixel: float) -> None:
    # findContours returns the centres of the outermost touched pixels, so even a
    # perfect mask's contour lies between 0 and 1 px inside the edge (0.5 on average).
    rng = np.random.default_rng(5)
    for _ in range(20):
        tip = Fingertip(rng.uniform(-0.2, 0.2, 2), rng.uniform(0, 6), rng.uniform(0.004, 0.02, 2))
        contour = _contour_pixels(render_mask(tip, surface))
        distance = tip.signed_distance(surface.pixel_to_world(contour)) / pixel
        assert np.abs(distance).max() <= 1.25
        assert -0.7 <= distance.mean() <= -0.25


def _centroid(mask: NDArray[np.uint8]) -> NDArray[np.float64]:
    moments = cv2.moments(mask, binaryImage=True)
    return np.array([[moments["m10"] / moments["m00"], moments["m01"] / moments["m00"]]])


def test_displacement_matches_the_finite_difference_of_two_renders(surface: Surface) -> None:
    # Elongated fingertips of a hand that turns about a pivot off to their side, over
    # 4 frames: their own rotation and their arc both matter at the pixel level.
    rng = np.random.default_rng(8)
    dt = 4 * surface.dt
    contour_errors, centroid_errors, first_order, straight_errors = [], [], [], []
    for _ in range(12):
        tip = Fingertip(rng.uniform(-0.15, 0.15, 2), rng.uniform(0, 6), radii=(0.005, 0.011))
        hand = Hand({"index": tip})
        hand.move_rigid((0.12, -0.06), 4.0, pivot=tip.centre + np.array([-0.05, -0.03]))
        first = render_mask(hand, surface)
        before = surface.pixel_to_world(_contour_pixels(first))
        centroid = surface.pixel_to_world(_centroid(first))
        moved = before + hand.displacement("index", before, dt)
        predicted = centroid + hand.displacement("index", centroid, dt)
        linear = before + dt * hand.point_velocity("index", before)
        straight = centroid + dt * hand.point_velocity("index", centroid)

        hand.advance(dt)
        second = render_mask(hand, surface)
        after = _contour_pixels(second)
        contour_errors.append(_polyline_distance(surface.world_to_pixel(moved), after).max())
        first_order.append(_polyline_distance(surface.world_to_pixel(linear), after).max())
        actual = _centroid(second)
        centroid_errors.append(np.linalg.norm(surface.world_to_pixel(predicted) - actual))
        straight_errors.append(np.linalg.norm(surface.world_to_pixel(straight) - actual))
    # Both contours are chains of pixel centres, each quantised by up to 1 px inward,
    # so 1 px plus the rendering error (measured: 1.10 px at worst over 200 poses).
    assert max(contour_errors) <= 1.25
    # Each render's centroid is quantised by up to about 0.25 px.
    assert max(centroid_errors) <= 0.5
    assert np.mean(centroid_errors) <= 0.2
    # First-order (velocity times dt) predictions miss by more: the test can tell.
    assert min(first_order) > 1.75
    assert min(straight_errors) > 1.0


def test_press_enlarges_the_rendered_tip(surface: Surface) -> None:
    tip = Fingertip((0.0, 0.0), 0.0, radii=(0.006, 0.008))
    counts = []
    for press in (0.0, 0.5, 1.0):
        tip.press = press
        counts.append(np.count_nonzero(render_mask(tip, surface)))
    assert counts[0] < counts[1] < counts[2]
    assert counts[2] / counts[0] == pytest.approx(1.15 * 1.3, rel=0.05)


def test_lifted_shapes_do_not_render(surface: Surface) -> None:
    hand = Hand({"thumb": Thumb((-0.05, 0.0)), "index": Fingertip((0.05, 0.0))})
    both = render_mask(hand, surface)
    hand.set_touching("thumb", False)
    index_only = render_mask(hand, surface)
    np.testing.assert_array_equal(index_only, render_mask(hand["index"], surface))
    assert np.count_nonzero(both) > np.count_nonzero(index_only) > 0
    hand.set_touching("index", False)
    assert not render_mask(hand, surface).any()


def test_union_of_overlapping_shapes_is_the_union_of_their_masks(surface: Surface) -> None:
    a = Fingertip((0.0, 0.0), 0.2)
    b = Palm((0.03, -0.02), 0.5, size=(0.05, 0.06))
    c = HandEdge((0.005, 0.01), 1.0)
    together = render_mask([a, b, c], surface)
    separate = [render_mask(shape, surface) > 0 for shape in (a, b, c)]
    np.testing.assert_array_equal(together > 0, separate[0] | separate[1] | separate[2])
    assert set(np.unique(together).tolist()) == {0, 255}
    assert together.dtype == np.uint8 and together.shape == surface.shape


def test_coverage_is_graded_along_the_edges(surface: Surface) -> None:
    coverage = render_coverage(Palm((0.0, 0.0), 0.3), surface)
    levels = np.unique(coverage)
    assert levels[0] == 0 and levels[-1] == 255 and len(levels) > 50


def test_shapes_off_the_table_are_clipped(surface: Surface, pixel: float) -> None:
    corner = np.array(surface.size) / 2 * (1, -1)
    tip = Fingertip(corner, 0.0, radii=(0.01, 0.01))
    quarter = np.count_nonzero(render_mask(tip, surface)) * pixel**2
    assert quarter == pytest.approx(tip.area / 4, rel=0.1)
    gone = [Fingertip((1.0, 0.0)), PolygonShape.rectangle((0.1, 0.1), (1e4, -1e4))]
    assert not render_mask(gone, surface).any()
    assert not render_mask([], surface).any()


def test_other_resolutions(pixel_centres: NDArray) -> None:
    small = Surface(size=(0.3, 0.2), resolution=(150, 100))
    mask = render_mask(Fingertip((0.0, 0.0), radii=(0.01, 0.01)), small)
    assert mask.shape == (100, 150)
    assert np.count_nonzero(mask) == pytest.approx(np.pi * 5.0**2, rel=0.1)


def test_noise_goes_through_the_given_generator(surface: Surface) -> None:
    hand = Hand({"index": Fingertip((0.0, 0.0))})
    noise = SensorNoise(salt_pepper=0.01, holes=2, jitter=1.0)
    a = render_mask(hand, surface, noise, np.random.default_rng(4))
    b = render_mask(hand, surface, noise, np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, render_mask(hand, surface))
    with pytest.raises(ValueError, match="rng"):
        render_mask(hand, surface, noise)


def test_bad_items_raise(surface: Surface) -> None:
    with pytest.raises(ValueError, match=r"hand_or_shapes\[1\]"):
        render_mask([Fingertip(), "a finger"], surface)  # type: ignore[list-item]
    # A shape 1 km wide over the table would take millions of outline vertices.
    with pytest.raises(ValueError, match="spans"):
        render_mask(PolygonShape.rectangle((1e3, 1e3)), surface)
    # Far away, it is simply not drawn.
    assert not render_mask(PolygonShape.rectangle((1e3, 1e3), (1e4, 0.0)), surface).any()
