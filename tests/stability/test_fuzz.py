"""Property test: random finger motions through the whole pipeline keep every
invariant and run the same twice.

Two regimes, each clean over 850 random examples before this test was written:
one fingertip anywhere, at up to 2 m/s, touching down and lifting at any frame;
and a slow hand of up to three fingertips (up to 0.1 m/s). Faster hands of several
fingers are not drawn: with up to three fingers, 3 of 300 examples at up to 3 m/s,
1 of 300 at up to 0.5 m/s and 2 of 400 at up to 0.25 m/s broke an invariant,
mostly a particle 1.1–2.8 mm inside the box (one finger shoves it into another).
The clearest is a hard case (``test_hard_cases``, "shoved into another finger").

Exploring locally (outside CI's fixed examples) later found a one-finger
counterexample: a 6.5 mm fingertip from (65.3, 0) mm at (-0.777, 0.346) m/s, down
at frame 2 and up at 8, drove a particle 1.13 mm into the 0.2 kg box's side in
frame 7 (tolerance 1 mm). It holds now (the deepest particle 0.01 mm in), and the
one-finger test plays it every time (``@example``). The long fuzz
(``graspenv bench --fuzz``) plays 10 000 harder episodes (README, "Stability on
hard cases").
"""

from __future__ import annotations

import math

from hypothesis import example, given, settings
from hypothesis import strategies as st

from graspenv.bench.invariants import first_difference

from . import _cases as cases
from ._cases import FingerPath

FRAMES = 24


@st.composite
def finger_paths(draw: st.DrawFn, max_speed: float) -> FingerPath:
    """A fingertip somewhere around the box (±8 cm), moving in any direction."""
    start = (draw(st.floats(-0.08, 0.08)), draw(st.floats(-0.08, 0.08)))
    speed = draw(st.floats(0.0, max_speed))
    heading = draw(st.floats(0.0, 2.0 * math.pi))
    down = draw(st.integers(0, FRAMES // 2))
    up = draw(st.integers(down + 1, FRAMES + 6))
    return FingerPath(
        start,
        (speed * math.cos(heading), speed * math.sin(heading)),
        radius=draw(st.floats(0.003, 0.012)),
        down=down,
        up=up,
    )


def _check(paths: list[FingerPath]) -> None:
    case = cases.random_fingers(paths, FRAMES, cases.box())
    first = cases.run(case)
    second = cases.run(case)
    assert first_difference(first.poses, second.poses) is None
    first.assert_ok()


@settings(deadline=None, max_examples=12)
@given(st.lists(finger_paths(max_speed=2.0), min_size=1, max_size=1))
@example([FingerPath((0.0653, 0.0), (-0.777, 0.346), radius=0.0065, down=2, up=8)])
def test_one_finger_at_any_speed_keeps_the_invariants(paths: list[FingerPath]) -> None:
    _check(paths)


@settings(deadline=None, max_examples=10)
@given(st.lists(finger_paths(max_speed=0.1), min_size=1, max_size=3))
def test_a_slow_hand_keeps_the_invariants(paths: list[FingerPath]) -> None:
    _check(paths)
