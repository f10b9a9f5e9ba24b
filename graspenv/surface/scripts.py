"""Scripted finger motions: a hand and a list of phases, played one camera frame at a
time.

A :class:`Phase` lasts a whole number of frames. For each finger it names it may set
the touch flag, move the finger by a translation (metres) while turning it by a
rotation (radians) about its own centre, and ramp its press; a :class:`GroupMotion`
moves several fingers as one rigid body about a pivot. Motions are given as totals
over the phase, so a phase ends exactly where it says whatever the frame rate: the
twist is the total divided by the phase's duration, and the shapes' exact motion law
(see :mod:`graspenv.surface.contact_shape`) makes the sum of the per-frame steps exact.

The builders at the end script the interactions the physics tests need: a two-finger
pinch that squeezes, turns, slides and lifts; a strike into an object's side; a rub
across its top; a third finger pushing a held object; a release. Their positions are
metres in the world frame and their durations are frames.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.surface import _checks
from graspenv.surface.geometry import Surface
from graspenv.surface.hand import Hand
from graspenv.surface.shapes import Fingertip

__all__ = [
    "FingerMotion",
    "GroupMotion",
    "Phase",
    "Script",
    "pinch_hand",
    "release",
    "side_strike",
    "third_finger_push",
    "top_rub",
    "two_finger_pinch",
]


def _pair(value: ArrayLike, name: str) -> tuple[float, float]:
    x, y = _checks.vector2(value, name).tolist()
    return (x, y)


@dataclass(frozen=True)
class FingerMotion:
    """What one finger does during a phase.

    Attributes:
        touching: put the finger down (True) or lift it (False) for the whole phase;
            None keeps its flag.
        translation: how far its centre moves over the phase in a straight line,
            metres, world frame, (x, y).
        rotation: how far it turns about its centre over the phase, radians.
        press: the press reached at the end of the phase, ramped linearly from the
            press at its start (fingertips only); None keeps the press.
    """

    touching: bool | None = None
    translation: tuple[float, float] = (0.0, 0.0)
    rotation: float = 0.0
    press: float | None = None

    def __post_init__(self) -> None:
        if self.touching is not None and not isinstance(self.touching, bool):
            raise ValueError(f"touching must be True, False or None, got {self.touching!r}")
        object.__setattr__(self, "translation", _pair(self.translation, "translation"))
        object.__setattr__(self, "rotation", _checks.finite(self.rotation, "rotation"))
        if self.press is not None:
            press = _checks.finite(self.press, "press")
            if not 0.0 <= press <= 1.0:
                raise ValueError(f"press must be in [0, 1], got {self.press!r}")
            object.__setattr__(self, "press", press)

    @property
    def moves(self) -> bool:
        """Whether the finger translates or turns."""
        return self.translation != (0.0, 0.0) or self.rotation != 0.0


@dataclass(frozen=True)
class GroupMotion:
    """Fingers moving together as one rigid body during a phase.

    Attributes:
        names: the fingers in the group.
        translation: how far the pivot moves over the phase, metres, world frame.
        rotation: how far the group turns about the pivot over the phase, radians.
        pivot: the point the group turns about, metres, world frame, at the start of
            the phase (it moves with the group); None is the mean of the fingers'
            centres at the start of the phase.
    """

    names: tuple[str, ...]
    translation: tuple[float, float] = (0.0, 0.0)
    rotation: float = 0.0
    pivot: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if isinstance(self.names, str):
            raise ValueError(f"names must be a sequence of finger names, got {self.names!r}")
        object.__setattr__(self, "names", tuple(self.names))
        if not self.names:
            raise ValueError("names must name at least one finger")
        object.__setattr__(self, "translation", _pair(self.translation, "translation"))
        object.__setattr__(self, "rotation", _checks.finite(self.rotation, "rotation"))
        if self.pivot is not None:
            object.__setattr__(self, "pivot", _pair(self.pivot, "pivot"))


@dataclass(frozen=True)
class Phase:
    """A stretch of frames with constant finger twists.

    Fingers that are in neither ``fingers`` nor ``group`` stay still and keep their
    touch flag and press. A finger may be in both: ``fingers`` then sets its touch
    flag and press, and must not move it.

    Attributes:
        frames: duration, camera frames, >= 1.
        fingers: per-finger motions by name.
        group: fingers that move as one rigid body, or None.
        name: a label (for :meth:`Script.phase_ranges`).
    """

    frames: int
    fingers: Mapping[str, FingerMotion] = field(default_factory=dict)
    group: GroupMotion | None = None
    name: str = ""

    def __post_init__(self) -> None:
        _checks.count(self.frames, f"phase {self.name!r} frames", minimum=1)
        fingers = dict(self.fingers)
        for finger, motion in fingers.items():
            if not isinstance(motion, FingerMotion):
                raise ValueError(
                    f"phase {self.name!r}: fingers[{finger!r}] must be a FingerMotion, "
                    f"got {type(motion).__name__}"
                )
        if self.group is not None:
            for finger in self.group.names:
                if finger in fingers and fingers[finger].moves:
                    raise ValueError(
                        f"phase {self.name!r}: finger {finger!r} moves both on its own and "
                        f"with the group"
                    )
        object.__setattr__(self, "fingers", MappingProxyType(fingers))


class Script:
    """A starting hand and the phases that move it.

    Args:
        hand: the hand at frame 0 (copied; the script never changes it).
        phases: played in order.

    Raises:
        ValueError: a phase names a finger the hand does not have, or sets the press
            of a shape that is not a fingertip.
    """

    def __init__(self, hand: Hand, phases: Sequence[Phase]) -> None:
        if not isinstance(hand, Hand):
            raise ValueError(f"hand must be a Hand, got {type(hand).__name__}")
        self._hand = hand.copy()
        self._phases = tuple(phases)
        for phase in self._phases:
            if not isinstance(phase, Phase):
                raise ValueError(f"phases must be Phase objects, got {type(phase).__name__}")
            named = list(phase.fingers) + list(phase.group.names if phase.group else ())
            for finger in named:
                if finger not in self._hand:
                    raise ValueError(
                        f"phase {phase.name!r} names finger {finger!r}; the hand has "
                        f"{self._hand.names}"
                    )
            for finger, motion in phase.fingers.items():
                if motion.press is not None and not isinstance(self._hand[finger], Fingertip):
                    raise ValueError(
                        f"phase {phase.name!r} sets the press of {finger!r}, which is not a "
                        f"Fingertip"
                    )

    @property
    def hand(self) -> Hand:
        """A copy of the starting hand."""
        return self._hand.copy()

    @property
    def phases(self) -> tuple[Phase, ...]:
        """The phases, in order."""
        return self._phases

    @property
    def n_frames(self) -> int:
        """Total duration, camera frames."""
        return sum(phase.frames for phase in self._phases)

    def phase_ranges(self) -> list[tuple[str, range]]:
        """Each phase's name and the frame indices it covers, in order."""
        ranges = []
        start = 0
        for phase in self._phases:
            ranges.append((phase.name, range(start, start + phase.frames)))
            start += phase.frames
        return ranges

    def then(self, *phases: Phase) -> Script:
        """A new script: this one followed by more phases."""
        return Script(self._hand, self._phases + phases)

    def frames(self, surface: Surface) -> Iterator[tuple[int, Hand]]:
        """Play the script one camera frame at a time.

        Args:
            surface: gives the frame interval ``surface.dt``.

        Yields:
            (frame index, hand): a copy of the hand as the camera sees it at that
            frame, carrying the twists that take it to the next frame, so
            ``hand.displacement(name, points, surface.dt)`` is the true motion of
            points on a finger until the next yielded frame.
        """
        dt = surface.dt
        hand = self._hand.copy()
        index = 0
        for phase in self._phases:
            duration = phase.frames * dt
            hand.stop()
            presses: dict[str, tuple[float, float]] = {}
            for name, motion in phase.fingers.items():
                if motion.touching is not None:
                    hand.set_touching(name, motion.touching)
                velocity = np.asarray(motion.translation) / duration
                hand[name].set_twist(velocity, motion.rotation / duration)
                tip = hand[name]
                if motion.press is not None and isinstance(tip, Fingertip):
                    presses[name] = (tip.press, motion.press)
            if phase.group is not None:
                group = phase.group
                pivot = (
                    np.mean([hand[name].centre for name in group.names], axis=0)
                    if group.pivot is None
                    else np.asarray(group.pivot)
                )
                hand.move_rigid(
                    np.asarray(group.translation) / duration,
                    group.rotation / duration,
                    pivot,
                    group.names,
                )
            for k in range(phase.frames):
                _set_presses(hand, presses, k / phase.frames)
                yield index, hand.copy()
                hand.advance(dt)
                index += 1
            _set_presses(hand, presses, 1.0)


def _set_presses(hand: Hand, presses: Mapping[str, tuple[float, float]], fraction: float) -> None:
    for name, (start, end) in presses.items():
        tip = hand[name]
        if isinstance(tip, Fingertip):
            tip.press = start + (end - start) * fraction


# -- builders ------------------------------------------------------------------------


def _direction(angle: float) -> NDArray[np.float64]:
    return np.array([math.cos(angle), math.sin(angle)])


def pinch_hand(
    centre: ArrayLike,
    gap: float,
    finger_radius: float = 0.007,
    axis_angle: float = 0.0,
) -> Hand:
    """Two lifted round fingertips, ``thumb`` and ``index``, either side of a point.

    Args:
        centre: the point between them, metres, world frame, (x, y).
        gap: distance between the fingertips' facing edges, metres (e.g. an object's
            width plus some clearance).
        finger_radius: fingertip radius, metres.
        axis_angle: direction from the thumb to the index finger, radians from the
            world x axis.
    """
    middle = _checks.vector2(centre, "centre")
    spacing = _checks.positive(gap, "gap")
    radius = _checks.positive(finger_radius, "finger_radius")
    axis = _direction(_checks.finite(axis_angle, "axis_angle"))
    offset = (0.5 * spacing + radius) * axis
    hand = Hand()
    for name, sign in (("thumb", -1.0), ("index", 1.0)):
        tip = Fingertip(middle + sign * offset, axis_angle, radii=(radius, radius))
        hand.add(name, tip, touching=False)
    return hand


def _frames(value: int, name: str) -> int:
    return _checks.count(value, name, minimum=0)


def _pinch(
    centre: ArrayLike,
    gap: float,
    finger_radius: float,
    axis_angle: float,
    approach: float,
    settle_frames: int,
    squeeze_frames: int,
) -> tuple[Hand, list[Phase]]:
    """The pinch builders' start: :func:`pinch_hand` and its ``touch`` and ``squeeze``.

    The arguments are the builders' own (see :func:`two_finger_pinch`).

    Returns:
        (hand, phases): the lifted fingertips, and the phases that touch down, then
        move both fingertips towards each other by ``approach``.
    """
    hand = pinch_hand(centre, gap, finger_radius, axis_angle)
    depth = _checks.non_negative(approach, "approach")
    inward = hand["index"].centre - hand["thumb"].centre
    inward /= np.linalg.norm(inward)
    phases = []
    down = FingerMotion(touching=True)
    if _frames(settle_frames, "settle_frames"):
        phases.append(Phase(settle_frames, {"thumb": down, "index": down}, name="touch"))
    if _frames(squeeze_frames, "squeeze_frames"):
        phases.append(
            Phase(
                squeeze_frames,
                {
                    "thumb": FingerMotion(touching=True, translation=tuple(depth * inward)),
                    "index": FingerMotion(touching=True, translation=tuple(-depth * inward)),
                },
                name="squeeze",
            )
        )
    elif depth > 0.0:
        raise ValueError("squeeze_frames must be >= 1 when approach > 0")
    if not phases:
        raise ValueError("settle_frames and squeeze_frames cannot both be 0")
    return hand, phases


def _hold(frames: int) -> list[Phase]:
    return [Phase(frames, name="hold")] if _frames(frames, "hold_frames") else []


def _lift(names: Sequence[str], frames: int, phase_name: str = "lift") -> list[Phase]:
    if not _frames(frames, "lift_frames"):
        return []
    return [Phase(frames, {name: FingerMotion(touching=False) for name in names}, name=phase_name)]


def _index_stroke(
    tip: Fingertip,
    settle_frames: int,
    move_frames: int,
    translation: ArrayLike,
    name: str,
    lift_frames: int,
) -> Script:
    """A hand of one lifted fingertip, ``index``, and the phases ``touch``, ``name``
    (it moves by ``translation``, metres, world frame, (x, y)), ``lift``;
    ``move_frames`` is checked as ``{name}_frames``."""
    hand = Hand()
    hand.add("index", tip, touching=False)
    phases = []
    if _frames(settle_frames, "settle_frames"):
        phases.append(Phase(settle_frames, {"index": FingerMotion(touching=True)}, name="touch"))
    frames = _checks.count(move_frames, f"{name}_frames", minimum=1)
    move = FingerMotion(touching=True, translation=_pair(translation, "translation"))
    phases.append(Phase(frames, {"index": move}, name=name))
    return Script(hand, phases + _lift(["index"], lift_frames))


def two_finger_pinch(
    centre: ArrayLike,
    gap: float,
    finger_radius: float = 0.007,
    approach: float = 0.003,
    turn: float = 0.0,
    slide: ArrayLike = (0.0, 0.0),
    *,
    axis_angle: float = 0.0,
    settle_frames: int = 5,
    squeeze_frames: int = 20,
    turn_frames: int = 30,
    slide_frames: int = 30,
    hold_frames: int = 0,
    lift_frames: int = 5,
) -> Script:
    """Two fingertips come down either side of a point, squeeze, turn, slide and lift.

    Phases (each skipped when its frame count is 0): ``touch`` (down, still),
    ``squeeze`` (each finger moves ``approach`` towards the other), ``turn`` (both
    turn by ``turn`` about their midpoint), ``slide`` (both move by ``slide``),
    ``hold`` (still), ``lift``.

    Args:
        centre: midpoint between the fingertips, metres, world frame, (x, y).
        gap: distance between the fingertips' facing edges at touch-down, metres.
        finger_radius: fingertip radius, metres.
        approach: how far each fingertip moves inward during the squeeze, metres.
        turn: rotation of the pair about its midpoint, radians, counter-clockwise.
        slide: translation of the pair, metres, world frame, (x, y).
        axis_angle: direction from the thumb to the index finger, radians.
        settle_frames, squeeze_frames, turn_frames, slide_frames, hold_frames,
            lift_frames: durations, camera frames.

    Raises:
        ValueError: a size is not positive, a duration is negative, or a motion is
            asked of a phase with 0 frames.
    """
    hand, phases = _pinch(
        centre, gap, finger_radius, axis_angle, approach, settle_frames, squeeze_frames
    )
    angle = _checks.finite(turn, "turn")
    shift = _pair(slide, "slide")
    pair = ("thumb", "index")
    if _frames(turn_frames, "turn_frames"):
        phases.append(Phase(turn_frames, group=GroupMotion(pair, rotation=angle), name="turn"))
    elif angle != 0.0:
        raise ValueError("turn_frames must be >= 1 when turn != 0")
    if _frames(slide_frames, "slide_frames"):
        phases.append(Phase(slide_frames, group=GroupMotion(pair, translation=shift), name="slide"))
    elif shift != (0.0, 0.0):
        raise ValueError("slide_frames must be >= 1 when slide is not zero")
    phases += _hold(hold_frames)
    phases += _lift(pair, lift_frames)
    return Script(hand, phases)


def release(
    centre: ArrayLike,
    gap: float,
    finger_radius: float = 0.007,
    approach: float = 0.003,
    *,
    axis_angle: float = 0.0,
    settle_frames: int = 5,
    squeeze_frames: int = 20,
    hold_frames: int = 20,
    stagger_frames: int = 0,
    lift_frames: int = 5,
) -> Script:
    """A pinch that squeezes, holds, then lets go.

    Phases: ``touch``, ``squeeze``, ``hold``, then, if ``stagger_frames`` > 0,
    ``lift index`` (the index finger lifts first while the thumb stays down) before
    ``lift`` (both up).

    Args:
        centre, gap, finger_radius, approach, axis_angle: as for
            :func:`two_finger_pinch`.
        settle_frames, squeeze_frames, hold_frames, stagger_frames, lift_frames:
            durations, camera frames.
    """
    hand, phases = _pinch(
        centre, gap, finger_radius, axis_angle, approach, settle_frames, squeeze_frames
    )
    phases += _hold(hold_frames)
    phases += _lift(["index"], _frames(stagger_frames, "stagger_frames"), "lift index")
    phases += _lift(["thumb", "index"], lift_frames)
    return Script(hand, phases)


def third_finger_push(
    centre: ArrayLike,
    gap: float,
    push_start: ArrayLike,
    push: ArrayLike,
    finger_radius: float = 0.007,
    approach: float = 0.003,
    *,
    axis_angle: float = 0.0,
    settle_frames: int = 5,
    squeeze_frames: int = 20,
    push_frames: int = 30,
    hold_frames: int = 10,
    lift_frames: int = 5,
) -> Script:
    """A pinch held still while a third fingertip (``middle``) pushes.

    Phases: ``touch``, ``squeeze``, ``push`` (``middle`` comes down at
    ``push_start`` and moves by ``push`` while the pinch holds), ``hold`` (all three
    still), ``lift`` (all three).

    Args:
        centre, gap, finger_radius, approach, axis_angle: as for
            :func:`two_finger_pinch`.
        push_start: where the third fingertip touches down, metres, world frame.
        push: its translation during the push, metres, world frame, (x, y).
        settle_frames, squeeze_frames, push_frames, hold_frames, lift_frames:
            durations, camera frames.
    """
    hand, phases = _pinch(
        centre, gap, finger_radius, axis_angle, approach, settle_frames, squeeze_frames
    )
    radius = _checks.positive(finger_radius, "finger_radius")
    start = _checks.vector2(push_start, "push_start")
    hand.add("middle", Fingertip(start, radii=(radius, radius)), touching=False)
    phases.append(
        Phase(
            _checks.count(push_frames, "push_frames", minimum=1),
            {"middle": FingerMotion(touching=True, translation=_pair(push, "push"))},
            name="push",
        )
    )
    phases += _hold(hold_frames)
    phases += _lift(["thumb", "index", "middle"], lift_frames)
    return Script(hand, phases)


def side_strike(
    contact_point: ArrayLike,
    direction: float,
    finger_radius: float = 0.007,
    clearance: float = 0.01,
    depth: float = 0.005,
    *,
    settle_frames: int = 3,
    strike_frames: int = 30,
    lift_frames: int = 5,
) -> Script:
    """A fingertip (``index``) that moves into the side of an object.

    It touches down ``clearance`` short of ``contact_point`` (its leading edge that
    far away), moves along ``direction`` until its leading edge is ``depth`` past
    the point, then lifts. Phases: ``touch``, ``strike``, ``lift``.

    Args:
        contact_point: a point on the object's side, metres, world frame, (x, y).
        direction: direction of travel, radians from the world x axis.
        finger_radius: fingertip radius, metres.
        clearance: gap between the fingertip and the point at touch-down, metres.
        depth: how far the leading edge goes past the point, metres.
        settle_frames, strike_frames, lift_frames: durations, camera frames.
    """
    point = _checks.vector2(contact_point, "contact_point")
    heading = _direction(_checks.finite(direction, "direction"))
    radius = _checks.positive(finger_radius, "finger_radius")
    before = _checks.non_negative(clearance, "clearance")
    travel = before + _checks.non_negative(depth, "depth")
    tip = Fingertip(point - (before + radius) * heading, direction, radii=(radius, radius))
    return _index_stroke(tip, settle_frames, strike_frames, travel * heading, "strike", lift_frames)


def top_rub(
    start: ArrayLike,
    translation: ArrayLike,
    finger_radius: float = 0.007,
    press: float = 0.5,
    *,
    settle_frames: int = 5,
    rub_frames: int = 40,
    lift_frames: int = 5,
) -> Script:
    """A fingertip (``index``) placed on top of an object and moved across it.

    Phases: ``touch`` (down at ``start``), ``rub`` (moves by ``translation``),
    ``lift``.

    Args:
        start: where the fingertip touches down, metres, world frame, (x, y).
        translation: its motion during the rub, metres, world frame, (x, y).
        finger_radius: fingertip radius at zero press, metres.
        press: fingertip press throughout, in [0, 1].
        settle_frames, rub_frames, lift_frames: durations, camera frames.
    """
    radius = _checks.positive(finger_radius, "finger_radius")
    tip = Fingertip(_checks.vector2(start, "start"), radii=(radius, radius), press=press)
    return _index_stroke(tip, settle_frames, rub_frames, translation, "rub", lift_frames)
