"""Mask validation, components, areas and the half-pixel outline offset."""

from __future__ import annotations

from collections.abc import Iterator

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from graspenv.bench.contact_scenes import ellipse_mask, ellipse_signed_distance
from graspenv.contacts import find_components, outline_from_chain, signed_area, validate_mask
from graspenv.contacts.extract import find_outlines, outlines_from_chains

Axes = tuple[float, float]


def _pixel_counts(mask: np.ndarray) -> list[int]:
    """Sizes of the 8-connected components, by labelling (the slow, sure way)."""
    count, _, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    return sorted(int(a) for a in stats[1:count, cv2.CC_STAT_AREA])


# -- validate_mask -------------------------------------------------------------------


def test_bool_mask_becomes_a_uint8_view_with_the_same_pixels() -> None:
    mask = np.zeros((4, 5), dtype=bool)
    mask[1, 2] = True
    image = validate_mask(mask, (4, 5))
    assert image.dtype == np.uint8
    assert np.shares_memory(image, mask)
    assert image.tolist() == mask.astype(np.uint8).tolist()


def test_uint8_mask_passes_unchanged() -> None:
    mask = np.zeros((4, 5), dtype=np.uint8)
    mask[0, 0] = 255
    assert validate_mask(mask) is mask


@pytest.mark.parametrize(
    ("mask", "given"),
    [
        ([[0, 1], [1, 0]], "got list"),
        (None, "got NoneType"),
        (np.zeros((4, 5, 3), np.uint8), "got 3-D array of shape (4, 5, 3)"),
        (np.zeros(20, np.uint8), "got 1-D array of shape (20,)"),
        (np.zeros((4, 5), np.float64), "got dtype float64"),
        (np.zeros((4, 5), np.int64), "got dtype int64"),
        (np.zeros((5, 4), np.uint8), "got shape (5, 4)"),
    ],
)
def test_bad_masks_raise_naming_expected_and_given(mask: object, given: str) -> None:
    with pytest.raises(ValueError) as err:
        validate_mask(mask, (4, 5))
    message = str(err.value)
    assert "(H, W) = (4, 5)" in message
    assert "bool or uint8" in message
    assert given in message


# -- components ----------------------------------------------------------------------


def test_single_pixel_is_its_square_footprint() -> None:
    mask = np.zeros((9, 9), np.uint8)
    mask[4, 6] = 1
    (component,) = find_components(mask)
    assert component.area == 1.0
    assert component.centroid.tolist() == [6.0, 4.0]
    assert sorted(map(tuple, component.outline.tolist())) == [
        (5.5, 3.5),
        (5.5, 4.5),
        (6.5, 3.5),
        (6.5, 4.5),
    ]
    assert abs(signed_area(component.outline)) == pytest.approx(1.0)


@pytest.mark.parametrize("length", [2, 3, 7])
@pytest.mark.parametrize("vertical", [False, True])
def test_one_pixel_wide_line_outlines_its_footprint(length: int, vertical: bool) -> None:
    mask = np.zeros((12, 12), np.uint8)
    mask[5, 2 : 2 + length] = 1
    if vertical:
        mask = np.ascontiguousarray(mask.T)
    (component,) = find_components(mask)
    assert component.area == length
    # The footprint, give or take the smoothing next to the caps.
    assert abs(signed_area(component.outline)) == pytest.approx(length, abs=0.4)
    lo, hi = component.outline.min(axis=0), component.outline.max(axis=0)
    extent = sorted((hi - lo).tolist())
    assert extent == pytest.approx([1.0, float(length)], abs=0.15)


def test_diagonal_line_and_spur_areas_count_pixels() -> None:
    mask = np.zeros((20, 20), np.uint8)
    for i in range(5):
        mask[2 + i, 2 + i] = 1  # diagonal line
    mask[10:15, 10:15] = 1
    mask[12, 15:19] = 1  # spur
    mask[15, 9] = 1  # diagonal neighbour
    components = find_components(mask)
    assert sorted(c.area for c in components) == [5.0, 30.0]
    for component in components:
        assert abs(signed_area(component.outline)) > 0.0


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), blobs=st.integers(1, 6))
def test_areas_equal_pixel_counts_of_random_blobs(seed: int, blobs: int) -> None:
    rng = np.random.default_rng(seed)
    mask = np.zeros((60, 80), np.uint8)
    for _ in range(blobs):
        centre = (int(rng.integers(5, 75)), int(rng.integers(5, 55)))
        axes = (int(rng.integers(0, 8)), int(rng.integers(0, 8)))
        cv2.ellipse(mask, centre, axes, float(rng.uniform(0, 180)), 0, 360, 1, -1)
    mask[rng.random(mask.shape) < 0.01] = 1  # speckle: single pixels and thin bits
    # Holes would count in a component's area but not in the labelling's.
    filled = mask.copy()
    cv2.floodFill(filled, np.zeros((62, 82), np.uint8), (0, 0), 2)
    if np.any(filled == 0):
        mask[filled == 0] = 1
    components = find_components(mask)
    assert sorted(int(c.area) for c in components) == _pixel_counts(mask)
    assert sum(c.area for c in components) == int(np.count_nonzero(mask))


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_components_come_in_raster_order_of_their_first_pixel(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mask = (rng.random((30, 40)) < 0.08).astype(np.uint8)
    firsts = []
    for component in find_components(mask):
        row = int(component.chain[:, 1].min())
        col = int(component.chain[component.chain[:, 1] == row, 0].min())
        firsts.append((row, col))
    assert firsts == sorted(firsts)
    assert len(firsts) == len(_pixel_counts(mask))


def test_min_area_drops_small_components() -> None:
    mask = np.zeros((20, 20), np.uint8)
    mask[2, 2] = 1
    mask[10:13, 10:13] = 1
    assert [c.area for c in find_components(mask, min_area=2)] == [9.0]
    assert [c.area for c in find_components(mask, min_area=9)] == [9.0]
    assert find_components(mask, min_area=10) == []


def test_outline_keeps_the_chain_orientation_and_lies_outside_it() -> None:
    chain = np.array([[3, 2], [3, 3], [3, 4], [4, 4], [5, 4], [5, 3], [5, 2], [4, 2]])
    outline = outline_from_chain(chain)
    assert np.sign(signed_area(outline)) == np.sign(signed_area(chain))
    # Between the traced centres (4 px²) and the 3 × 3 pixel footprint (9 px²): the
    # offset follows the smoothed normal, so a square's corners are rounded off.
    assert 7.0 < abs(signed_area(outline)) <= 9.0
    assert np.all(np.abs(outline - [4.0, 3.0]) <= 1.6)


# -- accuracy against an analytic ellipse -------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    centre=st.tuples(st.floats(28.0, 36.0), st.floats(28.0, 36.0)),
    axes=st.tuples(st.floats(6.0, 20.0), st.floats(6.0, 20.0)),
    angle=st.floats(0.0, np.pi),
)
def test_outline_is_within_a_pixel_of_the_analytic_ellipse(
    centre: tuple[float, float], axes: tuple[float, float], angle: float
) -> None:
    c = np.array(centre)
    mask = ellipse_mask((64, 64), c, axes, angle)
    (component,) = find_components(mask)
    outline = component.outline
    points = np.concatenate([outline, 0.5 * (outline + np.roll(outline, -1, axis=0))])
    error = ellipse_signed_distance(points, c, axes, angle)
    assert np.max(np.abs(error)) < 0.75  # pixels; measured worst 0.58
    # One ellipse's mean error depends on where it falls on the pixel grid (worst
    # measured 0.22 px, a circle centred on a pixel); the bias over many placements
    # is checked below.
    assert abs(float(np.mean(error))) < 0.3
    traced = ellipse_signed_distance(component.chain.astype(float), c, axes, angle)
    # Without the offset the traced centres sit about half a pixel inside.
    assert float(np.mean(traced)) < -0.25
    assert component.area == pytest.approx(np.pi * axes[0] * axes[1], rel=0.12)
    assert np.hypot(*(component.centroid - c)) < 0.35


def _fingertips(count: int = 60, seed: int = 20) -> Iterator[tuple[np.ndarray, Axes, float]]:
    """Random fingertip ellipses (centre, semi-axes, angle) on a 64 × 64 mask: 6-12 mm
    on the default table."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        c = rng.uniform(28.0, 36.0, size=2)
        axes = (float(rng.uniform(6.3, 12.6)), float(rng.uniform(6.3, 12.6)))
        yield c, axes, float(rng.uniform(0.0, np.pi))


def test_outline_has_no_bias_over_random_fingertips() -> None:
    outline_errors, traced_errors = [], []
    for c, axes, angle in _fingertips():
        (component,) = find_components(ellipse_mask((64, 64), c, axes, angle))
        outline_errors.append(ellipse_signed_distance(component.outline, c, axes, angle))
        traced_errors.append(ellipse_signed_distance(component.chain.astype(float), c, axes, angle))
    assert abs(float(np.mean(np.concatenate(outline_errors)))) < 0.05
    assert float(np.mean(np.concatenate(traced_errors))) == pytest.approx(-0.46, abs=0.05)


def test_shrink_free_smoothing_damps_the_staircase_without_shrinking() -> None:
    """``ContactConfig.outline_smoothing``: six pairs of Taubin's passes take the
    outline's scatter about the analytic edge down by a fifth (measured 0.186 px →
    0.146 px RMS over these 60 fingertips) and move its mean by 0.011 px; as many
    plain Laplacian passes would pull it about a third of a pixel inward."""
    plain, smoothed = [], []
    for c, axes, angle in _fingertips():
        mask = ellipse_mask((64, 64), c, axes, angle)
        for passes, errors in ((0, plain), (6, smoothed)):
            outline = find_outlines(mask, 0.0, passes).outlines.points
            errors.append(ellipse_signed_distance(outline, c, axes, angle))
    before, after = np.concatenate(plain), np.concatenate(smoothed)
    assert abs(float(after.mean() - before.mean())) < 0.03
    assert np.sqrt(np.mean(after**2)) < 0.85 * np.sqrt(np.mean(before**2))


@pytest.mark.parametrize("passes", [-1, 2.0, True])
def test_smoothing_passes_must_be_a_whole_number(passes: object) -> None:
    with pytest.raises(ValueError, match="passes"):
        find_outlines(np.ones((8, 8), np.uint8), 0.0, passes)  # type: ignore[arg-type]


@pytest.mark.parametrize("with_lines", [False, True])
def test_outlines_of_many_chains_equal_one_chain_at_a_time(with_lines: bool) -> None:
    """Blobs of every size (the three smallest too small to smooth) in one vectorised
    pass; with lines and a single pixel, which are capped one by one, mixed in."""
    mask = np.zeros((60, 80), np.uint8)
    cv2.ellipse(mask, (20, 20), (9, 6), 30.0, 0, 360, 1, -1)
    cv2.ellipse(mask, (60, 15), (5, 8), 0.0, 0, 360, 1, -1)
    mask[55:57, 60:62] = 1
    if with_lines:
        cv2.line(mask, (5, 45), (30, 50), 1, 1)
        mask[40, 70] = 1
    chains = [c.chain for c in find_components(mask)]
    assert len(chains) == (5 if with_lines else 3)
    outlines, bounds = outlines_from_chains(chains)
    assert len(bounds) == len(chains) + 1
    for i, chain in enumerate(chains):
        np.testing.assert_array_equal(
            outlines[bounds[i] : bounds[i + 1]], outline_from_chain(chain)
        )
