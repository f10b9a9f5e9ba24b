"""Contact shapes: outlines, inside tests, signed distances and exact motion."""

from __future__ import annotations

import math
from collections.abc import Callable

import cv2
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from graspenv.surface import (
    ContactShape,
    Fingertip,
    HandEdge,
    Palm,
    PolygonShape,
    Thumb,
)

SHAPES: dict[str, Callable[[], ContactShape]] = {
    "fingertip": lambda: Fingertip((0.01, -0.02), 0.4, radii=(0.005, 0.009), press=0.3),
    "round fingertip": lambda: Fingertip((0.0, 0.0), 0.0, radii=(0.006, 0.006)),
    "thumb": lambda: Thumb((-0.03, 0.05), -1.2),
    "palm": lambda: Palm((0.02, 0.01), 0.7, size=(0.07, 0.09), corner_radius=0.015),
    "square palm": lambda: Palm((0.0, 0.0), 0.2, size=(0.05, 0.03), corner_radius=0.0),
    "hand edge": lambda: HandEdge((-0.01, 0.0), 2.0, length=0.08, width=0.015),
    "card": lambda: PolygonShape.rectangle((0.054, 0.086), (0.03, -0.01), 0.3),
    "L": lambda: PolygonShape(
        [[0.0, 0.0], [0.04, 0.0], [0.04, 0.01], [0.01, 0.01], [0.01, 0.03], [0.0, 0.03]],
        (0.01, 0.02),
        -0.5,
    ),
}


def _signed_area(polygon: NDArray[np.float64]) -> float:
    x, y = polygon[:, 0], polygon[:, 1]
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _distance_to_polyline(points: NDArray[np.float64], polygon: NDArray[np.float64]) -> NDArray:
    a = polygon[None, :, :]
    edge = np.roll(polygon, -1, axis=0)[None, :, :] - a
    rel = points[:, None, :] - a
    t = np.clip(np.sum(rel * edge, axis=2) / np.sum(edge * edge, axis=2), 0.0, 1.0)
    gap = rel - t[..., None] * edge
    return np.hypot(gap[..., 0], gap[..., 1]).min(axis=1)


@pytest.mark.parametrize("kind", SHAPES)
def test_outline_is_counter_clockwise_on_the_boundary_with_short_edges(kind: str) -> None:
    shape = SHAPES[kind]()
    max_segment = 0.0007
    outline = shape.outline(max_segment)
    edges = np.hypot(*(np.roll(outline, -1, axis=0) - outline).T)
    assert edges.max() <= max_segment * (1 + 1e-12)
    assert edges.min() > 0.0
    assert _signed_area(outline) > 0.0
    np.testing.assert_allclose(shape.signed_distance(outline), 0.0, atol=1e-12)
    # Inscribed chords lose at most a sagitta band along the perimeter.
    perimeter = edges.sum()
    assert shape.area - perimeter * max_segment <= _signed_area(outline) <= shape.area + 1e-12


@pytest.mark.parametrize("kind", SHAPES)
def test_signed_distance_matches_a_brute_force_distance(kind: str) -> None:
    shape = SHAPES[kind]()
    rng = np.random.default_rng(3)
    points = shape.centre + rng.uniform(-1.3, 1.3, (400, 2)) * shape.bounding_radius
    fine = shape.outline(2e-5)
    brute = _distance_to_polyline(points, fine)
    distance = shape.signed_distance(points)
    # The fine outline is inscribed, so it may sit up to its sagitta inside.
    np.testing.assert_allclose(np.abs(distance), brute, atol=1e-7)
    assert np.array_equal(distance <= 0.0, shape.contains(points))
    inside = np.array(
        [
            cv2.pointPolygonTest(fine.astype(np.float32).reshape(-1, 1, 2), tuple(p), False)
            for p in points.astype(np.float32).tolist()
        ]
    )
    clear = np.abs(distance) > 1e-6
    assert np.array_equal(shape.contains(points)[clear], inside[clear] >= 0)


def test_ellipse_distance_on_its_axes_and_at_its_centre() -> None:
    tip = Fingertip((0.0, 0.0), 0.0, radii=(0.004, 0.01))
    points = np.array([[0.0, 0.0], [0.0, 0.02], [0.01, 0.0], [0.0, 0.002], [0.0, 0.009]])
    distance = tip.signed_distance(points)
    # On the major axis near the centre the nearest boundary point leaves the axis.
    b, a = 0.01, 0.004
    y = 0.002
    ratio = b * y / (b * b - a * a)
    near = -math.hypot(b * ratio - y, a * math.sqrt(1 - ratio * ratio))
    np.testing.assert_allclose(distance, [-0.004, 0.01, 0.006, near, -0.001], atol=1e-12)


@settings(deadline=None, max_examples=40)
@example(a=0.019503165510178132, b=0.015625, xy=(1.60169927028697e-130, 0.015625))
@given(
    a=st.floats(0.002, 0.02),
    b=st.floats(0.002, 0.02),
    xy=st.tuples(st.floats(-0.04, 0.04), st.floats(-0.04, 0.04)),
)
def test_ellipse_distance_is_exact_anywhere(a: float, b: float, xy: tuple[float, float]) -> None:
    tip = Fingertip((0.0, 0.0), 0.0, radii=(a, b))
    point = np.array([xy])
    brute = _distance_to_polyline(point, tip.outline(2e-6))
    distance = tip.signed_distance(point)[0]
    assert abs(abs(distance) - brute[0]) <= 1e-8
    # A point on the boundary, to rounding, may be classified either way.
    if abs(distance) > 1e-12:
        assert (distance <= 0) == tip.contains(point)[0]


def test_press_enlarges_the_fingertip_along_the_finger_most() -> None:
    tip = Fingertip(radii=(0.006, 0.008), spread=0.3)
    areas, axes = [], []
    for press in (0.0, 0.5, 1.0):
        tip.press = press
        areas.append(tip.area)
        axes.append(tip.semi_axes)
    assert areas[0] < areas[1] < areas[2]
    assert axes[0] == pytest.approx((0.006, 0.008))
    assert axes[2] == pytest.approx((0.006 * 1.15, 0.008 * 1.3))
    pressed = tip.outline(0.0005)
    tip.press = 0.0
    # The pressed outline encloses the light one.
    assert not tip.contains(pressed).any()
    assert Thumb().area > Fingertip().area


@pytest.mark.parametrize("press", [-0.01, 1.01, float("nan"), float("inf")])
def test_press_outside_zero_to_one_raises(press: float) -> None:
    with pytest.raises(ValueError, match="press"):
        Fingertip(press=press)
    tip = Fingertip()
    with pytest.raises(ValueError, match="press"):
        tip.press = press


@pytest.mark.parametrize(
    ("make", "word"),
    [
        (lambda: Fingertip(centre=(0.0, float("nan"))), "centre"),
        (lambda: Fingertip(centre=(0.0, 0.0, 0.0)), "centre"),
        (lambda: Fingertip(angle=float("inf")), "angle"),
        (lambda: Fingertip(radii=(0.0, 0.01)), "radii"),
        (lambda: Fingertip(spread=-0.1), "spread"),
        (lambda: Fingertip(linear_velocity=(1.0,)), "linear"),
        (lambda: Palm(size=(0.05, -0.01)), "size"),
        (lambda: Palm(size=(0.05, 0.04), corner_radius=0.03), "corner_radius"),
        (lambda: HandEdge(length=0.02, width=0.03), "width"),
        (lambda: HandEdge(length=float("nan")), "length"),
        (lambda: PolygonShape([[0, 0], [1, 0]]), "at least 3"),
        (lambda: PolygonShape([[0, 0], [1, 0], [2, 0]]), "zero area"),
        (lambda: PolygonShape([[0, 0], [1, 0], [1, 0], [0, 1]]), "repeat"),
        (lambda: PolygonShape([[0, 0], [2, 2], [2, 0], [0, 1]]), "simple"),
        (lambda: PolygonShape([[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]]), "simple"),
        (lambda: PolygonShape(np.zeros((4, 3))), "shape"),
    ],
)
def test_bad_shape_arguments_raise_naming_the_value(make: Callable[[], object], word: str) -> None:
    with pytest.raises(ValueError, match=word):
        make()


def test_bad_call_arguments_raise() -> None:
    tip = Fingertip()
    with pytest.raises(ValueError, match="max_segment"):
        tip.outline(0.0)
    with pytest.raises(ValueError, match="points"):
        tip.contains(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="points"):
        tip.displacement([[0.0, float("nan")]], 0.1)
    with pytest.raises(ValueError, match="dt"):
        tip.advance(float("nan"))
    with pytest.raises(ValueError, match="pivot"):
        tip.set_twist((0.0, 0.0), 1.0, pivot=(1.0, 2.0, 3.0))


def test_polygon_orientation_is_normalised_and_centroid_found() -> None:
    clockwise = [[0.0, 0.0], [0.0, 0.02], [0.04, 0.02], [0.04, 0.0]]
    shape = PolygonShape(clockwise)
    assert _signed_area(shape.vertices) > 0.0
    assert shape.area == pytest.approx(0.0008)
    placed = PolygonShape.from_world(np.array(clockwise) + np.array([0.1, -0.1]))
    np.testing.assert_allclose(placed.centre, [0.12, -0.09], atol=1e-15)
    assert placed.contains([[0.12, -0.09]])[0]
    assert not placed.contains([[0.0, 0.0]])[0]


# -- motion ------------------------------------------------------------------------------

twists = st.tuples(
    st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-10.0, 10.0)
)  # vx, vy (m/s), ω (rad/s)


@settings(deadline=None, max_examples=60)
@given(
    twist=twists,
    pivot=st.none() | st.tuples(st.floats(-0.1, 0.1), st.floats(-0.1, 0.1)),
    dt=st.floats(0.0, 0.2),
)
def test_displacement_is_where_advance_takes_material_points(
    twist: tuple[float, float, float], pivot: tuple[float, float] | None, dt: float
) -> None:
    shape = Fingertip((0.02, -0.01), 0.3, radii=(0.005, 0.009))
    shape.set_twist(twist[:2], twist[2], pivot=pivot)
    points = shape.outline(0.002)
    local = shape.to_local(points)
    moved = points + shape.displacement(points, dt)
    shape.advance(dt)
    np.testing.assert_allclose(shape.to_world(local), moved, atol=1e-12)


@settings(deadline=None, max_examples=40)
@given(twist=twists, dt1=st.floats(0.0, 0.1), dt2=st.floats(0.0, 0.1))
def test_motion_composes_and_centre_moves_in_a_straight_line(
    twist: tuple[float, float, float], dt1: float, dt2: float
) -> None:
    once = Palm((0.01, 0.02), 0.1, linear_velocity=twist[:2], angular_velocity=twist[2])
    twice = once.copy()
    once.advance(dt1 + dt2)
    twice.advance(dt1)
    twice.advance(dt2)
    np.testing.assert_allclose(once.centre, twice.centre, atol=1e-13)
    assert once.angle == pytest.approx(twice.angle, abs=1e-12)
    # With the default pivot (the centre) the centre goes straight at v.
    np.testing.assert_allclose(
        once.centre, np.array([0.01, 0.02]) + np.array(twist[:2]) * (dt1 + dt2), atol=1e-13
    )
    assert once.angle == pytest.approx(0.1 + twist[2] * (dt1 + dt2), abs=1e-12)


def test_point_velocity_is_the_first_order_displacement() -> None:
    shape = HandEdge((0.0, 0.05), 0.2, linear_velocity=(0.1, -0.2), angular_velocity=3.0)
    points = shape.outline(0.005)
    expected = np.array([0.1, -0.2]) + 3.0 * np.stack(
        [-(points[:, 1] - 0.05), points[:, 0]], axis=-1
    )
    np.testing.assert_allclose(shape.point_velocity(points), expected, atol=1e-14)
    dt = 1e-5
    np.testing.assert_allclose(shape.displacement(points, dt) / dt, expected, atol=1e-5)
    # Over a finite step the exact motion differs from the linear one.
    assert np.abs(shape.displacement(points, 0.1) - 0.1 * expected).max() > 1e-4


def test_pivot_keeps_centre_velocity_and_turns_about_the_pivot() -> None:
    shape = Fingertip((0.05, 0.0))
    shape.set_twist((0.0, 0.5), 10.0, pivot=(0.0, 0.0))
    np.testing.assert_allclose(shape.linear_velocity, [0.0, 0.5], atol=1e-15)
    shape.advance(math.pi / 20)  # a quarter turn about the origin
    np.testing.assert_allclose(shape.centre, [0.0, 0.05], atol=1e-15)
    np.testing.assert_allclose(shape.linear_velocity, [-0.5, 0.0], atol=1e-15)
    # Placing the shape resets the pivot but keeps the velocities.
    shape.set_pose(centre=(0.1, 0.1), angle=0.0)
    np.testing.assert_allclose(shape.pivot, [0.1, 0.1])
    np.testing.assert_allclose(shape.linear_velocity, [-0.5, 0.0], atol=1e-15)
    assert shape.angular_velocity == 10.0


def test_copy_is_independent() -> None:
    original = Fingertip((0.0, 0.0), press=0.2, linear_velocity=(1.0, 0.0))
    twin = original.copy()
    assert isinstance(twin, Fingertip)
    twin.advance(0.1)
    twin.press = 0.9
    np.testing.assert_allclose(original.centre, [0.0, 0.0])
    assert original.press == 0.2
    centre = original.centre
    centre[0] = 5.0
    assert original.centre[0] == 0.0
