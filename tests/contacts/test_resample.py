"""Even arc-length resampling and orientation of closed polylines."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from graspenv.bench.contact_scenes import Finger, ellipse_mask_world
from graspenv.contacts import find_components, orient_ccw, resample_closed, signed_area
from graspenv.contacts.resample import follow_kernel, orient_ccw_batch, resample_closed_batch
from graspenv.geometry import Polylines
from graspenv.surface.geometry import Surface

from .strategies import fingertip_axes, fingertips

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # counter-clockwise


def _arc_steps(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Arc length along ``polyline`` from each resampled point to the next."""
    step = np.roll(polyline, -1, axis=0) - polyline
    length = np.linalg.norm(step, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(length)])
    positions = []
    for point in points:
        t = np.clip(np.einsum("ij,ij->i", point - polyline, step) / length**2, 0.0, 1.0)
        gap = np.linalg.norm(polyline + t[:, None] * step - point, axis=1)
        i = int(np.argmin(gap))
        positions.append(arc[i] + t[i] * length[i])
    return np.diff(np.array([*positions, positions[0] + arc[-1]])) % arc[-1]


def test_square_points_sit_exactly_on_the_arc_length_grid() -> None:
    points = resample_closed(SQUARE, 0.25)
    assert len(points) == 16
    assert points[0].tolist() == [0.0, 0.0]
    assert points[4].tolist() == [1.0, 0.0]
    assert points[6].tolist() == [1.0, 0.5]
    np.testing.assert_allclose(_arc_steps(points, SQUARE), 0.25, atol=1e-12)


def test_point_count_rounds_the_perimeter_and_spacing_is_exact_along_it() -> None:
    points = resample_closed(SQUARE, 0.3)  # perimeter 4 -> 13 points, 0.3077 apart
    assert len(points) == 13
    np.testing.assert_allclose(_arc_steps(points, SQUARE), 4.0 / 13, atol=1e-12)


def test_repeated_closing_vertex_is_harmless() -> None:
    closed = np.vstack([SQUARE, SQUARE[:1]])
    np.testing.assert_allclose(resample_closed(closed, 0.25), resample_closed(SQUARE, 0.25))


def test_start_takes_the_closest_point_of_the_polyline() -> None:
    points = resample_closed(SQUARE, 0.25, start=np.array([1.3, 0.4]))
    np.testing.assert_allclose(points[0], [1.0, 0.4])
    np.testing.assert_allclose(points[1], [1.0, 0.65])
    np.testing.assert_allclose(_arc_steps(points, SQUARE), 0.25, atol=1e-12)


def test_tiny_polyline_still_gives_three_distinct_points() -> None:
    points = resample_closed(SQUARE * 1e-3, 0.004)
    assert len(points) == 3
    assert len({tuple(p) for p in points.tolist()}) == 3
    assert signed_area(points) > 0.0


@pytest.mark.parametrize(
    ("polyline", "spacing", "start"),
    [
        (np.zeros((3, 2)), 0.1, None),
        (np.zeros((3, 3)), 0.1, None),
        (np.zeros((0, 2)), 0.1, None),
        (SQUARE, 0.0, None),
        (SQUARE, float("nan"), None),
        (SQUARE, 0.1, np.zeros(3)),
        (np.array([[0.0, 0.0], [np.inf, 1.0]]), 0.1, None),
    ],
)
def test_bad_input_raises(polyline: np.ndarray, spacing: float, start: np.ndarray | None) -> None:
    with pytest.raises(ValueError):
        resample_closed(polyline, spacing, start)


def test_orient_ccw_reverses_clockwise_keeping_the_first_vertex() -> None:
    clockwise = SQUARE[[0, 3, 2, 1]]
    assert signed_area(clockwise) == pytest.approx(-1.0)
    oriented = orient_ccw(clockwise)
    assert oriented.tolist() == SQUARE.tolist()
    assert orient_ccw(SQUARE).tolist() == SQUARE.tolist()


def _ellipse(centre: np.ndarray, a: float, b: float, angle: float, n: int) -> np.ndarray:
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    c, s = np.cos(angle), np.sin(angle)
    x, y = a * np.cos(t), b * np.sin(t)
    return centre + np.stack([c * x - s * y, s * x + c * y], axis=1)


@settings(max_examples=60, deadline=None)
@given(
    axes=fingertip_axes,
    angle=st.floats(0.0, np.pi),
    spacing=st.floats(0.002, 0.004),
    vertices=st.integers(40, 400),
    clockwise=st.booleans(),
    start=st.floats(0.0, 2.0 * np.pi),
)
def test_spacing_within_ten_percent_and_orientation_kept(
    axes: tuple[float, float],
    angle: float,
    spacing: float,
    vertices: int,
    clockwise: bool,
    start: float,
) -> None:
    polyline = _ellipse(np.array([0.2, -0.1]), *axes, angle, vertices)
    if clockwise:
        polyline = polyline[::-1]
    begin = np.array([0.2 + 0.05 * np.cos(start), -0.1 + 0.05 * np.sin(start)])
    points = resample_closed(polyline, spacing, start=begin)
    perimeter = np.linalg.norm(np.roll(polyline, -1, axis=0) - polyline, axis=1).sum()
    assert len(points) >= 5
    assert abs(perimeter / len(points) - spacing) <= 0.1 * spacing
    # Fingertip curvature (radius >= 3 mm) keeps every chord within 10 % of its arc.
    chords = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    assert np.all(chords >= 0.9 * spacing)
    assert np.all(chords <= 1.1 * spacing)
    assert np.sign(signed_area(points)) == np.sign(signed_area(polyline))
    ccw = orient_ccw(points)
    assert signed_area(ccw) > 0.0
    assert ccw[0].tolist() == points[0].tolist()


@settings(max_examples=25, deadline=None)
@given(finger=fingertips)
def test_rendered_fingertip_contour_keeps_the_spacing(finger: Finger) -> None:
    surface = Surface()
    mask = ellipse_mask_world(surface, *finger)
    (component,) = find_components(mask.view(np.uint8))
    outline = orient_ccw(surface.pixel_to_world(component.outline))
    points = resample_closed(outline, 0.004)
    perimeter = np.linalg.norm(np.roll(outline, -1, axis=0) - outline, axis=1).sum()
    assert abs(perimeter / len(points) - 0.004) <= 0.1 * 0.004
    np.testing.assert_allclose(_arc_steps(points, outline), perimeter / len(points), rtol=1e-9)
    # Straight-line gaps are shorter than arcs, most where a chord cuts a corner of
    # the rasterised blob (measured: 1 % of them below 0.92 of the spacing, none
    # below 0.87).
    chords = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    assert abs(float(np.mean(chords)) - 0.004) <= 0.1 * 0.004
    assert np.all(chords >= 0.8 * 0.004)
    assert np.all(chords <= 1.1 * 0.004)
    assert signed_area(points) > 0.0


def _laid_end_to_end(polylines: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    bounds = np.concatenate([[0], np.cumsum([len(p) for p in polylines])])
    return np.concatenate(polylines), bounds


@settings(max_examples=60)
@given(
    st.lists(
        st.tuples(
            st.integers(3, 40),  # vertices
            st.floats(0.004, 0.03),  # radius, metres
            st.booleans(),  # a start point?
            st.integers(0, 2**16),  # seed of the wobble and the start
        ),
        min_size=1,
        max_size=8,
    )
)
def test_batch_resampling_equals_one_polyline_at_a_time(shapes: list) -> None:
    polylines, starts = [], []
    for vertices, radius, has_start, seed in shapes:
        rng = np.random.default_rng(seed)
        t = np.sort(rng.uniform(0.0, 2 * np.pi, vertices))
        r = radius * (1.0 + 0.2 * rng.uniform(-1.0, 1.0, vertices))
        centre = rng.uniform(-0.2, 0.2, 2)
        polylines.append(centre + np.stack([r * np.cos(t), r * np.sin(t)], axis=1))
        starts.append(polylines[-1][rng.integers(vertices)] + 0.001 if has_start else [np.nan] * 2)
    points, bounds = _laid_end_to_end(polylines)
    resampled, cuts = resample_closed_batch(points, bounds, 0.003, np.array(starts))
    assert len(cuts) == len(polylines) + 1
    for i, polyline in enumerate(polylines):
        start = None if np.isnan(starts[i][0]) else np.array(starts[i])
        np.testing.assert_allclose(
            resampled[cuts[i] : cuts[i + 1]], resample_closed(polyline, 0.003, start), atol=1e-15
        )


def test_batch_orientation_turns_only_the_clockwise_ones() -> None:
    clockwise = SQUARE[::-1].copy()
    points, bounds = _laid_end_to_end([SQUARE, clockwise, SQUARE + 5.0])
    oriented = orient_ccw_batch(points, bounds)
    for i, polyline in enumerate([SQUARE, clockwise, SQUARE + 5.0]):
        np.testing.assert_array_equal(oriented[bounds[i] : bounds[i + 1]], orient_ccw(polyline))
    already = _laid_end_to_end([SQUARE, SQUARE])
    assert orient_ccw_batch(*already) is already[0]  # nothing to turn: no copy


def test_batch_resampling_rejects_a_zero_perimeter_polyline() -> None:
    points, bounds = _laid_end_to_end([SQUARE, np.zeros((3, 2))])
    with pytest.raises(ValueError, match="zero perimeter"):
        resample_closed_batch(points, bounds, 0.25)


def test_batch_functions_check_bounds_and_starts_before_the_kernels() -> None:
    """The compiled kernels do not check indices: the public batch functions do."""
    points = np.concatenate([SQUARE, SQUARE + 2.0])
    good = np.array([0, 4, 8])
    with pytest.raises(ValueError, match="rise strictly from 0 to 8"):
        resample_closed_batch(points, np.array([0, 4, 12]), 0.25)
    with pytest.raises(ValueError, match="rise strictly from 0 to 8"):
        orient_ccw_batch(points, np.array([0, 4, 4, 8]))
    with pytest.raises(ValueError, match="starts must have shape"):
        resample_closed_batch(points, good, 0.25, np.zeros((1, 2)))
    with pytest.raises(ValueError, match="points must be finite"):
        resample_closed_batch(np.full((8, 2), np.nan), good, 0.25)
    assert resample_closed_batch(points, good, 0.25)[1].tolist() == [0, 16, 32]


# -- points that land where they were predicted (follow_kernel) ---------------------


def _circle(radius: float, sides: int, phase: float = 0.0) -> np.ndarray:
    angle = phase + np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    return radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _follow(outline: np.ndarray, spacing: float, predicted: np.ndarray) -> np.ndarray:
    polylines = Polylines(outline, np.array([0, len(outline)]))
    points, bounds = follow_kernel(
        polylines, spacing, Polylines(predicted, np.array([0, len(predicted)]))
    )
    assert list(bounds) == [0, len(points)]
    return points


def _angles(points: np.ndarray) -> np.ndarray:
    return np.degrees(np.arctan2(points[:, 1], points[:, 0]))


def test_followed_points_stay_where_predicted_when_the_perimeter_changes() -> None:
    # An 8 mm fingertip's outline, then the same tip with a 0.4 mm bulge on one
    # side (as a pixelated outline changes from frame to frame), drawn with other
    # vertices. Evenly resampled from the same first point, every point shifts by
    # its share of the bulge's extra length (up to 0.7°); followed, each point moves
    # out along the predicted contour's normal and stays on its angle, the points
    # on the bulge too (put on the bulge's nearest point instead, they moved 0.23°).
    before = resample_closed(_circle(0.008, 64), 0.004)
    angle = 0.01 + np.linspace(0.0, 2.0 * np.pi, 60, endpoint=False)
    radius = 0.008 + 0.0004 * np.exp(-(((angle - np.pi) / 0.3) ** 2))
    after = radius[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    followed = _follow(after, 0.004, before)
    evenly = resample_closed(after, 0.004, start=before[0])
    assert len(followed) == len(before) == 13
    off_followed = np.abs((_angles(followed) - _angles(before) + 180) % 360 - 180)
    off_evenly = np.abs((_angles(evenly) - _angles(before) + 180) % 360 - 180)
    assert off_followed.max() < 0.02
    assert np.median(off_evenly) > 0.4


def test_a_gap_is_filled_and_crowded_points_are_dropped() -> None:
    outline = _circle(0.008, 64)
    points = resample_closed(outline, 0.004)
    # One point missing: the gap of two spacings gets one point in its middle.
    gapped = _follow(outline, 0.004, np.delete(points, 5, axis=0))
    assert len(gapped) == len(points)
    np.testing.assert_allclose(gapped[5], points[5], atol=1e-4)
    # A point 0.5 mm after another (an eighth of the spacing) is dropped.
    crowded = np.insert(points, 3, points[2] + np.array([0.0, 0.0005]), axis=0)
    kept = _follow(outline, 0.004, crowded)
    assert len(kept) == len(points)
    np.testing.assert_allclose(kept, points, atol=1e-4)


def test_landings_out_of_order_fall_back_to_even_resampling() -> None:
    outline = _circle(0.008, 64)
    points = resample_closed(outline, 0.004)
    shuffled = points[[0, 2, 1, *range(3, len(points))]]
    np.testing.assert_allclose(
        _follow(outline, 0.004, shuffled), resample_closed(outline, 0.004, start=points[0])
    )
