"""Scripted finger motions: phases end where they say, touch flags and presses follow
the script, and each frame's twist is the true motion to the next frame."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from graspenv.surface import (
    FingerMotion,
    Fingertip,
    GroupMotion,
    Hand,
    Palm,
    Phase,
    Script,
    Surface,
    release,
    render_mask,
    side_strike,
    third_finger_push,
    top_rub,
    two_finger_pinch,
)


def _frames(script: Script, surface: Surface) -> list[Hand]:
    frames = list(script.frames(surface))
    assert [index for index, _ in frames] == list(range(script.n_frames))
    return [hand for _, hand in frames]


def _first_frames(script: Script) -> dict[str, int]:
    return {name: frames.start for name, frames in script.phase_ranges()}


def test_pinch_squeezes_turns_slides_and_lifts(surface: Surface) -> None:
    script = two_finger_pinch(
        (0.02, -0.01), gap=0.06, finger_radius=0.007, approach=0.004, turn=math.pi / 2,
        slide=(0.05, 0.01), settle_frames=4, squeeze_frames=10, turn_frames=20,
        slide_frames=15, hold_frames=3, lift_frames=2,
    )  # fmt: skip
    assert [name for name, _ in script.phase_ranges()] == [
        "touch", "squeeze", "turn", "slide", "hold", "lift",
    ]  # fmt: skip
    assert script.n_frames == 4 + 10 + 20 + 15 + 3 + 2
    hands = _frames(script, surface)
    start = _first_frames(script)
    first = hands[0]
    assert first.is_touching("thumb") and first.is_touching("index")
    np.testing.assert_allclose(first["thumb"].centre, [0.02 - 0.037, -0.01], atol=1e-15)
    np.testing.assert_allclose(first["index"].centre, [0.02 + 0.037, -0.01], atol=1e-15)

    squeezed = hands[start["turn"]]
    np.testing.assert_allclose(squeezed["thumb"].centre, [0.02 - 0.033, -0.01], atol=1e-12)
    np.testing.assert_allclose(squeezed["index"].centre, [0.02 + 0.033, -0.01], atol=1e-12)

    turned = hands[start["slide"]]
    np.testing.assert_allclose(turned["thumb"].centre, [0.02, -0.01 - 0.033], atol=1e-12)
    np.testing.assert_allclose(turned["index"].centre, [0.02, -0.01 + 0.033], atol=1e-12)
    assert turned["index"].angle == pytest.approx(math.pi / 2, abs=1e-12)

    slid = hands[start["hold"]]
    np.testing.assert_allclose(slid["index"].centre, [0.07, -0.01 + 0.033 + 0.01], atol=1e-12)
    np.testing.assert_allclose(hands[-1]["index"].centre, slid["index"].centre, atol=1e-15)

    # The pair keeps its spacing throughout the turn and the slide.
    for hand in hands[start["turn"] : start["lift"]]:
        spacing = np.linalg.norm(hand["index"].centre - hand["thumb"].centre)
        assert spacing == pytest.approx(0.066, abs=1e-12)
    lifted = hands[start["lift"]]
    assert not lifted.is_touching("thumb") and not lifted.is_touching("index")
    assert not render_mask(lifted, surface).any()
    assert np.count_nonzero(render_mask(hands[0], surface)) > 0


def test_each_frame_carries_the_true_motion_to_the_next(surface: Surface) -> None:
    script = two_finger_pinch((0.0, 0.0), 0.05, turn=1.0, slide=(0.02, -0.03)).then(
        Phase(6, {"thumb": FingerMotion(translation=(0.01, 0.0), rotation=0.5)}, name="wiggle")
    )
    hands = _frames(script, surface)
    for before, after in itertools.pairwise(hands):
        for name in before.names:
            points = before[name].outline(0.003)
            local = before[name].to_local(points)
            moved = points + before.displacement(name, points, surface.dt)
            np.testing.assert_allclose(after[name].to_world(local), moved, atol=1e-12)


def test_yielded_hands_are_snapshots(surface: Surface) -> None:
    script = top_rub((0.0, 0.0), (0.05, 0.0), rub_frames=10)
    hands = _frames(script, surface)
    assert hands[0]["index"].centre[0] == 0.0
    assert hands[-1]["index"].centre[0] == pytest.approx(0.05)
    # Playing again gives the same frames; the script's own hand never moves.
    again = _frames(script, surface)
    for a, b in zip(hands, again, strict=True):
        np.testing.assert_array_equal(a["index"].centre, b["index"].centre)
    np.testing.assert_array_equal(script.hand["index"].centre, [0.0, 0.0])


def test_press_ramps_over_a_phase(surface: Surface) -> None:
    hand = Hand({"index": Fingertip((0.0, 0.0))})
    script = Script(
        hand,
        [
            Phase(4, {"index": FingerMotion(press=1.0)}, name="press"),
            Phase(2, name="hold"),
        ],
    )
    presses = [h["index"].press for h in _frames(script, surface)]  # type: ignore[attr-defined]
    assert presses == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0, 1.0])


def test_group_turns_about_its_pivot(surface: Surface) -> None:
    hand = Hand({"a": Fingertip((0.05, 0.0)), "b": Fingertip((0.0, 0.05)), "c": Palm()})
    group = GroupMotion(("a", "b"), rotation=math.pi, pivot=(0.0, 0.0))
    script = Script(hand, [Phase(12, group=group), Phase(1, name="after")])
    last = _frames(script, surface)[-1]
    np.testing.assert_allclose(last["a"].centre, [-0.05, 0.0], atol=1e-12)
    np.testing.assert_allclose(last["b"].centre, [0.0, -0.05], atol=1e-12)
    np.testing.assert_array_equal(last["c"].centre, [0.0, 0.0])


def test_side_strike_goes_from_clearance_to_depth(surface: Surface) -> None:
    script = side_strike(
        (0.03, 0.0), direction=math.pi, finger_radius=0.006, clearance=0.01, depth=0.004
    )
    hands = _frames(script, surface)
    start = _first_frames(script)
    # Moving in -x, its leading edge is its centre minus the radius along x.
    assert hands[0]["index"].centre[0] - 0.006 == pytest.approx(0.03 + 0.01)
    struck = hands[start["lift"]]
    assert struck["index"].centre[0] - 0.006 == pytest.approx(0.03 - 0.004)
    assert struck["index"].centre[1] == pytest.approx(0.0, abs=1e-15)
    assert not struck.is_touching("index") and hands[0].is_touching("index")


def test_third_finger_pushes_while_the_pinch_holds(surface: Surface) -> None:
    script = third_finger_push((0.0, 0.0), 0.04, push_start=(0.0, -0.05), push=(0.0, 0.02))
    hands = _frames(script, surface)
    ranges = dict(script.phase_ranges())
    for index in ranges["squeeze"]:
        assert not hands[index].is_touching("middle")
    held = hands[ranges["push"].start]
    for index in ranges["push"]:
        hand = hands[index]
        assert hand.is_touching("middle") and hand.is_touching("thumb")
        np.testing.assert_array_equal(hand["thumb"].centre, held["thumb"].centre)
    np.testing.assert_allclose(hands[ranges["hold"].start]["middle"].centre, [0.0, -0.03])
    assert not any(touching for _, _, touching in hands[-1])


def test_release_can_lift_one_finger_first(surface: Surface) -> None:
    script = release((0.0, 0.0), 0.04, hold_frames=5, stagger_frames=3, lift_frames=2)
    ranges = dict(script.phase_ranges())
    hands = _frames(script, surface)
    staggered = hands[ranges["lift index"].start]
    assert staggered.is_touching("thumb") and not staggered.is_touching("index")
    assert not hands[ranges["lift"].start].is_touching("thumb")


@pytest.mark.parametrize(
    ("build", "word"),
    [
        (lambda: two_finger_pinch((0, 0), 0.05, turn=1.0, turn_frames=0), "turn_frames"),
        (lambda: two_finger_pinch((0, 0), 0.05, slide=(0.1, 0), slide_frames=0), "slide_frames"),
        (lambda: two_finger_pinch((0, 0), 0.05, squeeze_frames=0), "squeeze_frames"),
        (lambda: two_finger_pinch((0, 0), 0.0), "gap"),
        (lambda: two_finger_pinch((0, 0), 0.05, finger_radius=-0.01), "finger_radius"),
        (lambda: two_finger_pinch((0, 0), 0.05, lift_frames=-1), "lift_frames"),
        (lambda: two_finger_pinch((0, float("nan")), 0.05), "centre"),
        (lambda: side_strike((0, 0), 0.0, depth=-0.01), "depth"),
        (lambda: top_rub((0, 0), (0.1, 0), press=2.0), "press"),
        (lambda: third_finger_push((0, 0), 0.04, (0, 0), (0, 0), push_frames=0), "push_frames"),
        (lambda: Phase(0), "frames"),
        (lambda: FingerMotion(press=1.5), "press"),
        (lambda: FingerMotion(translation=(0.1,)), "translation"),  # type: ignore[arg-type]
        (lambda: FingerMotion(touching=1), "touching"),  # type: ignore[arg-type]
        (lambda: GroupMotion("ab"), "names"),  # type: ignore[arg-type]
        (lambda: GroupMotion(()), "names"),
        (
            lambda: Phase(
                3, {"a": FingerMotion(translation=(0.1, 0))}, GroupMotion(("a",), rotation=1.0)
            ),
            "group",
        ),
        (lambda: Script(Hand({"a": Fingertip()}), [Phase(3, {"b": FingerMotion()})]), "'b'"),
        (lambda: Script(Hand({"p": Palm()}), [Phase(3, {"p": FingerMotion(press=0.5)})]), "press"),
    ],
)
def test_bad_scripts_raise_naming_the_value(build: object, word: str) -> None:
    with pytest.raises(ValueError, match=word):
        build()  # type: ignore[operator]
