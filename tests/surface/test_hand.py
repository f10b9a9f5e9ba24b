"""Hands: named shapes, touch flags and rigid motion of the whole hand."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from graspenv.surface import Fingertip, Hand, HandEdge, Palm, Thumb


def _hand() -> Hand:
    return Hand(
        {
            "thumb": Thumb((-0.05, -0.02), 0.8),
            "index": Fingertip((0.0, 0.04), 0.1),
            "middle": Fingertip((0.02, 0.045), -0.1),
            "palm": Palm((0.0, -0.05), 0.0),
        }
    )


def test_iteration_is_ordered_with_touch_flags() -> None:
    hand = _hand()
    hand.set_touching("middle", False)
    listed = [(name, touching) for name, _shape, touching in hand]
    assert listed == [("thumb", True), ("index", True), ("middle", False), ("palm", True)]
    assert hand.names == ("thumb", "index", "middle", "palm")
    assert hand.touching_shapes() == [hand["thumb"], hand["index"], hand["palm"]]
    assert not hand.is_touching("middle")
    assert "palm" in hand and "ring" not in hand and len(hand) == 4
    hand.add("edge", HandEdge((0.1, 0.0)), touching=False)
    assert hand.names[-1] == "edge" and not hand.is_touching("edge")
    assert isinstance(hand.remove("edge"), HandEdge) and "edge" not in hand


def test_bad_names_and_shapes_raise() -> None:
    hand = _hand()
    with pytest.raises(ValueError, match="already"):
        hand.add("index", Fingertip())
    with pytest.raises(ValueError, match="non-empty"):
        hand.add("", Fingertip())
    with pytest.raises(ValueError, match="ContactShape"):
        hand.add("ring", "not a shape")  # type: ignore[arg-type]
    with pytest.raises(KeyError, match="ring"):
        hand["ring"]
    with pytest.raises(KeyError, match="ring"):
        hand.set_touching("ring", True)
    with pytest.raises(KeyError, match="ring"):
        hand.move_rigid((0.0, 0.0), 1.0, (0.0, 0.0), names=["ring"])
    with pytest.raises(ValueError, match="pivot"):
        hand.move_rigid((0.0, 0.0), 1.0, (0.0, float("nan")))


@settings(deadline=None, max_examples=50)
@given(
    velocity=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)),
    omega=st.floats(-12.0, 12.0),
    pivot=st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2)),
    frames=st.integers(1, 60),
)
def test_move_rigid_moves_the_hand_as_one_body(
    velocity: tuple[float, float], omega: float, pivot: tuple[float, float], frames: int
) -> None:
    hand = _hand()
    hand.set_touching("middle", False)  # lifted shapes move with the hand too
    start = {name: (shape.centre, shape.angle) for name, shape, _ in hand}
    hand.move_rigid(velocity, omega, pivot)
    for name, shape, _ in hand:
        r = start[name][0] - np.array(pivot)
        expected = np.array(velocity) + omega * np.array([-r[1], r[0]])
        np.testing.assert_allclose(shape.linear_velocity, expected, atol=1e-14)
        assert shape.angular_velocity == omega
    dt = 1.0 / 60.0
    for _ in range(frames):
        hand.advance(dt)
    t = frames * dt
    c, s = np.cos(omega * t), np.sin(omega * t)
    turn = np.array([[c, -s], [s, c]])
    moved_pivot = np.array(pivot) + np.array(velocity) * t
    for name, shape, _ in hand:
        centre, angle = start[name]
        np.testing.assert_allclose(shape.centre, moved_pivot + turn @ (centre - pivot), atol=1e-12)
        assert shape.angle == pytest.approx(angle + omega * t, abs=1e-10)
    for (a, _, _), (b, _, _) in itertools.combinations(hand, 2):
        before = np.linalg.norm(start[a][0] - start[b][0])
        after = np.linalg.norm(hand[a].centre - hand[b].centre)
        assert after == pytest.approx(before, abs=1e-12)


def test_move_rigid_on_some_names_leaves_the_others() -> None:
    hand = _hand()
    hand["palm"].set_twist((0.1, 0.0), 0.0)
    hand.move_rigid((0.0, 0.2), 2.0, (0.0, 0.0), names=["index", "middle"])
    assert hand["thumb"].angular_velocity == 0.0
    np.testing.assert_allclose(hand["palm"].linear_velocity, [0.1, 0.0])
    assert hand["index"].angular_velocity == 2.0


def test_displacement_of_a_named_shape_predicts_its_motion() -> None:
    hand = _hand()
    hand.move_rigid((0.1, -0.05), 4.0, (0.0, 0.0))
    points = hand["index"].outline(0.002)
    local = hand["index"].to_local(points)
    dt = 0.05
    predicted = points + hand.displacement("index", points, dt)
    np.testing.assert_allclose(
        hand.point_velocity("index", points), hand["index"].point_velocity(points)
    )
    hand.advance(dt)
    np.testing.assert_allclose(hand["index"].to_world(local), predicted, atol=1e-13)


def test_copy_is_independent() -> None:
    hand = _hand()
    hand.move_rigid((0.1, 0.0), 1.0, (0.0, 0.0))
    twin = hand.copy()
    twin.advance(0.5)
    twin.set_touching("thumb", False)
    assert hand.is_touching("thumb")
    np.testing.assert_allclose(hand["index"].centre, [0.0, 0.04])
    assert twin["index"] is not hand["index"]
    assert twin.names == hand.names


def test_stop_zeroes_every_twist() -> None:
    hand = _hand()
    hand.move_rigid((0.1, 0.0), 1.0, (0.0, 0.0))
    hand.stop()
    before = {name: shape.centre for name, shape, _ in hand}
    hand.advance(1.0)
    for name, shape, _ in hand:
        np.testing.assert_array_equal(shape.centre, before[name])
