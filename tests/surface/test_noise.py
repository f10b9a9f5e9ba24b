"""Sensor noise: off by default, repeatable for a seeded generator, and each kind
changes the mask the way its documentation says."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from graspenv.surface import Fingertip, Palm, SensorNoise, Surface, render_mask


@pytest.fixture
def mask(surface: Surface) -> NDArray[np.uint8]:
    """Three fingertips and a palm."""
    shapes = [Fingertip((x, 0.05), 0.0) for x in (-0.04, 0.0, 0.04)] + [Palm((0.0, -0.05))]
    return render_mask(shapes, surface)


def _distance_to_edge(mask: NDArray[np.uint8]) -> NDArray[np.float32]:
    """Each pixel's distance, in pixels, to the nearest pixel of the other kind."""
    touched = (mask > 0).astype(np.uint8)
    inside = cv2.distanceTransform(touched, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    outside = cv2.distanceTransform(1 - touched, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    return np.maximum(inside, outside)


def test_noise_is_off_by_default(mask: NDArray[np.uint8]) -> None:
    noise = SensorNoise()
    assert not noise.enabled and not noise.needs_rng
    np.testing.assert_array_equal(noise.apply(mask), mask)
    np.testing.assert_array_equal(noise.apply(mask > 0, np.random.default_rng(0)), mask)


@pytest.mark.parametrize(
    "kind",
    [
        {"salt_pepper": 0.02},
        {"holes": 3, "hole_radius": 4.0},
        {"jitter": 2.0},
        {"blur_sigma": 1.0, "salt_pepper": 0.01, "holes": 2, "jitter": 1.5},
    ],
)
def test_same_seed_same_noise_other_seed_other_noise(
    kind: dict[str, float], mask: NDArray[np.uint8]
) -> None:
    noise = SensorNoise(**kind)  # type: ignore[arg-type]
    original = mask.copy()
    first = noise.apply(mask, np.random.default_rng(42))
    again = noise.apply(mask, np.random.default_rng(42))
    other = noise.apply(mask, np.random.default_rng(43))
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    assert not np.array_equal(first, mask)
    np.testing.assert_array_equal(mask, original)  # the input is left alone
    assert first.dtype == np.uint8 and set(np.unique(first).tolist()) <= {0, 255}


def test_blur_erases_specks_and_rounds_corners() -> None:
    mask = np.zeros((60, 60), np.uint8)
    mask[10:40, 10:40] = 255  # a square
    mask[50, 50] = 255  # a one-pixel speck
    mask[45, 5:55] = 255  # a one-pixel line
    blurred = SensorNoise(blur_sigma=1.5).apply(mask)
    assert blurred[50, 50] == 0 and not blurred[45].any()
    assert blurred[10, 10] == 0 and blurred[25, 25] == 255  # corner cut, middle kept
    assert blurred[25, 10] == 255  # straight edges stay put
    assert np.count_nonzero(blurred) == pytest.approx(30 * 30, rel=0.05)


def test_salt_and_pepper_flips_the_given_fraction(mask: NDArray[np.uint8]) -> None:
    probability = 0.05
    noisy = SensorNoise(salt_pepper=probability).apply(mask, np.random.default_rng(1))
    flipped = np.count_nonzero((noisy > 0) != (mask > 0))
    n = mask.size
    assert abs(flipped - probability * n) < 5 * np.sqrt(n * probability * (1 - probability))
    # Both ways: salt outside the contacts and pepper inside them.
    assert np.any((noisy > 0) & (mask == 0)) and np.any((noisy == 0) & (mask > 0))


def test_holes_are_punched_only_inside_contacts(mask: NDArray[np.uint8]) -> None:
    count, radius = 4, 3.0
    holed = SensorNoise(holes=count, hole_radius=radius).apply(mask, np.random.default_rng(2))
    removed = (mask > 0) & (holed == 0)
    assert not np.any((holed > 0) & (mask == 0))
    assert 0 < np.count_nonzero(removed) <= count * np.pi * (radius + 1) ** 2
    n_labels, _ = cv2.connectedComponents(removed.astype(np.uint8))
    assert 1 <= n_labels - 1 <= count


def test_jitter_moves_edges_by_at_most_its_amplitude(mask: NDArray[np.uint8]) -> None:
    amplitude = 2.0
    jittered = SensorNoise(jitter=amplitude).apply(mask, np.random.default_rng(3))
    changed = (jittered > 0) != (mask > 0)
    assert np.count_nonzero(changed) > 20
    # Every changed pixel lies within the amplitude (plus the half-pixel border) of
    # the original edge; interiors and the background far away are untouched.
    assert _distance_to_edge(mask)[changed].max() <= amplitude + 0.5
    # Edges move both outward and inward.
    assert np.any(changed & (mask > 0)) and np.any(changed & (mask == 0))


def test_random_noise_needs_a_generator(mask: NDArray[np.uint8]) -> None:
    with pytest.raises(ValueError, match="rng"):
        SensorNoise(jitter=1.0).apply(mask)
    # Blur alone draws nothing.
    assert SensorNoise(blur_sigma=1.0).apply(mask).shape == mask.shape


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("blur_sigma", -1.0),
        ("blur_sigma", float("nan")),
        ("salt_pepper", 1.5),
        ("salt_pepper", -0.1),
        ("holes", -1),
        ("holes", 2.5),
        ("holes", True),
        ("hole_radius", 0.0),
        ("jitter", float("inf")),
        ("jitter_scale", 0.0),
    ],
)
def test_bad_parameters_raise_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        SensorNoise(**{field: value})  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [np.zeros((4, 4, 3), np.uint8), np.zeros((4, 4), np.float32)])
def test_bad_masks_raise(bad: NDArray[np.generic]) -> None:
    with pytest.raises(ValueError, match="mask"):
        SensorNoise(blur_sigma=1.0).apply(bad)


def test_scaled_noise_scales_each_kind_and_keeps_the_shapes() -> None:
    from graspenv.surface.noise import TABLE_NOISE

    di = TABLE_NOISE["di"]
    twice = di.scaled(2.0)
    assert twice.blur_sigma == 2 * di.blur_sigma and twice.jitter == 2 * di.jitter
    assert twice.salt_pepper == 2 * di.salt_pepper and twice.holes == 2 * di.holes
    assert (twice.hole_radius, twice.jitter_scale) == (di.hole_radius, di.jitter_scale)
    assert SensorNoise(salt_pepper=0.6).scaled(3.0).salt_pepper == 1.0
    assert not di.scaled(0.0).enabled
    with pytest.raises(ValueError, match="factor"):
        di.scaled(-1.0)
    # The FTIR table's noise is the milder of the two in every kind.
    ftir = TABLE_NOISE["ftir"]
    for key in ("blur_sigma", "salt_pepper", "jitter"):
        assert getattr(ftir, key) < getattr(di, key)
