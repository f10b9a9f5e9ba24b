"""TUIO 1.1: cursors and blobs, alive and fseq as the specification says, several
sources, silence, and datagrams that are not TUIO at all."""

from __future__ import annotations

import math
import random

import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from graspenv.live.touches import MAX_TOUCHES, Touch, TouchBoard
from graspenv.live.tuio import SOURCE_TIMEOUT, TuioReceiver
from tests.live._helpers import tuio_cursor_bundle


def _bundle(address: str, *messages: tuple[object, ...]) -> bytes:
    bundle = OscBundleBuilder(IMMEDIATELY)
    for args in messages:
        m = OscMessageBuilder(address)
        for a in args:
            m.add_arg(a)
        bundle.add_content(m.build())
    return bundle.build().dgram


class _Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _receiver() -> tuple[TuioReceiver, TouchBoard, _Clock]:
    board, clock = TouchBoard(), _Clock()
    return TuioReceiver(board, clock), board, clock


def test_cursors_become_default_fingertips_and_lift_when_not_alive() -> None:
    tuio, board, _ = _receiver()
    tuio.feed(tuio_cursor_bundle(1, {5: (0.25, 0.5), 7: (0.75, 0.5)}), "host:1")
    assert board.touches() == [Touch(0.25, 0.5), Touch(0.75, 0.5)]
    # Cursor 7 keeps its place without a new set; 5 is no longer alive.
    tuio.feed(_bundle("/tuio/2Dcur", ("alive", 7), ("fseq", 2)), "host:1")
    assert board.touches() == [Touch(0.75, 0.5)]
    tuio.feed(tuio_cursor_bundle(3, {}), "host:1")
    assert board.touches() == []
    assert tuio.dropped == 0


def test_blobs_are_ellipses_of_their_width_height_and_angle() -> None:
    tuio, board, _ = _receiver()
    blob = ("set", 3, 0.5, 0.4, 0.7, 0.04, 0.02, 0.0006, 0.0, 0.0, 0.0, 0.0, 0.0)
    tuio.feed(_bundle("/tuio/2Dblb", ("alive", 3), blob, ("fseq", 10)), "host:1")
    (touch,) = board.touches()
    assert (touch.x, touch.y, touch.angle) == pytest.approx((0.5, 0.4, 0.7))
    assert (touch.rx, touch.ry) == pytest.approx((0.02, 0.01))


def test_a_late_frame_is_dropped_and_a_restart_or_unsequenced_frame_is_not() -> None:
    tuio, board, _ = _receiver()
    tuio.feed(tuio_cursor_bundle(500, {1: (0.125, 0.125)}), "h:1")
    tuio.feed(tuio_cursor_bundle(499, {1: (0.875, 0.875)}), "h:1")  # late: UDP reordered
    assert board.touches() == [Touch(0.125, 0.125)]
    tuio.feed(tuio_cursor_bundle(-1, {1: (0.1875, 0.1875)}), "h:1")  # unsequenced: applied
    assert board.touches() == [Touch(0.1875, 0.1875)]
    tuio.feed(tuio_cursor_bundle(3, {1: (0.3125, 0.3125)}), "h:1")  # far below: a restart
    assert board.touches() == [Touch(0.3125, 0.3125)]
    tuio.feed(tuio_cursor_bundle(4, {1: (0.4375, 0.4375)}), "h:1")
    assert board.touches() == [Touch(0.4375, 0.4375)]


def test_sources_touch_at_once_with_their_own_session_ids() -> None:
    tuio, board, clock = _receiver()
    tuio.feed(tuio_cursor_bundle(1, {1: (0.125, 0.125)}, source="left@10.0.0.125"), "h:1")
    tuio.feed(tuio_cursor_bundle(1, {1: (0.875, 0.875)}, source="right@10.0.0.2"), "h:1")
    tuio.feed(tuio_cursor_bundle(1, {1: (0.5, 0.5)}), "h:2")  # no source: its address
    assert sorted(board.touches(), key=lambda t: t.x) == [
        Touch(0.125, 0.125),
        Touch(0.5, 0.5),
        Touch(0.875, 0.875),
    ]
    tuio.feed(tuio_cursor_bundle(2, {}, source="left@10.0.0.125"), "h:1")
    assert len(board.touches()) == 2
    # A tracker that falls silent has its touches lifted.
    clock.now = 1.0
    tuio.feed(tuio_cursor_bundle(3, {1: (0.875, 0.875)}, source="right@10.0.0.2"), "h:1")
    clock.now = 1.0 + SOURCE_TIMEOUT + 0.125
    tuio.expire()
    assert board.touches() == []


@pytest.mark.parametrize(
    "messages, reason",
    [
        ((("set", 1, math.nan, 0.5, 0.0, 0.0, 0.0), ("fseq", 1)), "finite"),
        ((("set", 1, 1.5, 0.5, 0.0, 0.0, 0.0), ("fseq", 1)), "x must be"),
        ((("set", 1, 0.5), ("fseq", 1)), "6 arguments"),
        ((("set", "one", 0.5, 0.5, 0.0, 0.0, 0.0), ("fseq", 1)), "int32"),
        ((("alive", *range(MAX_TOUCHES + 1)), ("fseq", 1)), "alive ids"),
        ((("wobble", 1),), "unknown command"),
        (((3,),), "command string"),
    ],
)
def test_bad_messages_are_dropped_and_counted(
    messages: tuple[tuple[object, ...], ...], reason: str
) -> None:
    tuio, board, _ = _receiver()
    tuio.feed(_bundle("/tuio/2Dcur", *messages), "h:1")
    assert tuio.dropped >= 1 and reason in tuio.last_error
    assert board.touches() == []


def test_random_datagrams_never_raise() -> None:
    tuio, board, _ = _receiver()
    rng = random.Random(0)
    good = tuio_cursor_bundle(1, {1: (0.5, 0.5), 2: (0.25, 0.75)})
    for i in range(2000):
        if i % 2:
            data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 200)))
        else:  # a valid bundle with bytes flipped
            flipped = bytearray(good)
            for _ in range(rng.randrange(1, 6)):
                flipped[rng.randrange(len(flipped))] = rng.randrange(256)
            data = bytes(flipped)
        tuio.feed(data, "h:1")
    assert tuio.datagrams == 2000 and tuio.dropped > 0
    assert len(board.touches()) <= MAX_TOUCHES
    for touch in board.touches():
        assert 0.0 <= touch.x <= 1.0 and 0.0 <= touch.y <= 1.0
