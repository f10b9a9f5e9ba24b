"""The hard cases of the stability suite: scenes and masks that stress the pipeline.

A :class:`Case` is a scene, the masks of every frame (rendered from a synthetic
hand, or drawn pixel by pixel) and the fastest finger speed, from which the
invariant checker derives its object speed bound. :func:`run` plays a case through
a fresh :class:`~graspenv.simulation.Simulation` and returns the checker.

Every case runs on a small table (0.32 × 0.24 m at 320 × 240 pixels: 1 mm pixels,
like the default table's 0.95 mm) so masks are small and pushes reach the edge soon.
Positions are metres in the world frame (origin at the table centre), durations
camera frames.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from graspenv.bench.fuzz import FingerPath, finger_hands
from graspenv.bench.invariants import InvariantChecker, hand_speed
from graspenv.config import ObjectConfig, SceneConfig, at_fidelity, load_config, to_dict
from graspenv.simulation import Simulation
from graspenv.surface import (
    FingerMotion,
    Fingertip,
    GroupMotion,
    Hand,
    Palm,
    Phase,
    Script,
    SensorNoise,
    Surface,
    release,
    render_mask,
    side_strike,
    two_finger_pinch,
)

Mask = NDArray[np.uint8]

TABLE_SIZE = (0.32, 0.24)
TABLE_PIXELS = (320, 240)
FINGER_RADIUS = 0.008
#: Gap between a fingertip and the face it squeezes, at touch-down, metres.
CLEARANCE = 0.004
_TIP = (FINGER_RADIUS, FINGER_RADIUS)


@dataclass(frozen=True)
class Case:
    """A scene and what the table sees in each frame.

    Attributes:
        name: for messages.
        scene: the configuration.
        masks: the mask of every frame, for the scene's surface.
        finger_speed: the fastest finger point, m/s (the speed bound's base).
    """

    name: str
    scene: SceneConfig
    masks: Callable[[Surface], list[Mask]]
    finger_speed: float

    def with_sections(self, **sections: Any) -> Case:
        """The same case with scene sections overridden (e.g. a guard switched off).

        The masks stay those of the original scene: change the physics, proxy and
        contact sections, not the surface.
        """
        return replace(self, scene=self.scene.replace(**sections))

    def at_fidelity(self, fidelity: str) -> Case:
        """The same case at one of the environments' presets
        (:func:`graspenv.config.at_fidelity`: the reference's contour refined from the
        case's own); the masks stay the original scene's, as for :meth:`with_sections`."""
        return replace(self, scene=at_fidelity(self.scene, fidelity))


def run(case: Case) -> InvariantChecker:
    """Play a case through a fresh simulation, checking every frame."""
    with Simulation(case.scene) as sim:
        checker = InvariantChecker(sim, case.finger_speed)
        for mask in case.masks(sim.surface):
            sim.step(mask)
            checker.check()
    return checker


def box(mass: float = 0.2, friction: float = 0.5, **fields: Any) -> ObjectConfig:
    """The 6 × 6 × 3 cm box of the paper's interactions (default: 0.2 kg at the centre)."""
    fields.setdefault("name", "box")
    return ObjectConfig(
        shape="box", size=(0.06, 0.06, 0.03), mass=mass, friction=friction, **fields
    )


def scene(*objects: ObjectConfig, **sections: Any) -> SceneConfig:
    """The default settings on the small table, with these objects and overrides."""
    surface = {"size": TABLE_SIZE, "resolution": TABLE_PIXELS, **sections.pop("surface", {})}
    return load_config(None, surface=surface, objects=[to_dict(o) for o in objects], **sections)


def played(
    name: str,
    config: SceneConfig,
    hands: Sequence[Hand],
    extra_frames: int = 0,
    noise: SensorNoise | None = None,
    seed: int = 0,
) -> Case:
    """A case that renders a hand per frame, then ``extra_frames`` empty frames."""
    frozen = list(hands)

    def masks(surface: Surface) -> list[Mask]:
        rng = np.random.default_rng(seed)
        drawn = [render_mask(hand, surface, noise, rng) for hand in frozen]
        return drawn + [np.zeros(surface.shape, np.uint8)] * extra_frames

    return Case(name, config, masks, hand_speed(frozen))


def scripted(
    name: str,
    config: SceneConfig,
    script: Script,
    extra_frames: int = 0,
    noise: SensorNoise | None = None,
    seed: int = 0,
) -> Case:
    """A case played by a scripted hand, then ``extra_frames`` empty frames."""
    hands = [hand for _, hand in script.frames(Surface.from_config(config.surface))]
    return played(name, config, hands, extra_frames, noise, seed)


def _down(names: Sequence[str], frames: int = 2) -> Phase:
    return Phase(frames, {n: FingerMotion(touching=True) for n in names}, name="touch")


def _up(names: Sequence[str], frames: int = 2) -> Phase:
    return Phase(frames, {n: FingerMotion(touching=False) for n in names}, name="lift")


# -- grasps ------------------------------------------------------------------------


def pinch(
    obj: ObjectConfig,
    config: SceneConfig,
    name: str,
    depth: float = 0.003,
    turn: float = math.pi / 2,
    slide: tuple[float, float] = (0.0, 0.03),
    noise: SensorNoise | None = None,
    **frames: int,
) -> Case:
    """Two fingertips squeeze ``depth`` into the object (0.3 mm a frame), turn the
    pair by ``turn`` in 30 frames, slide it by ``slide`` in 15 and lift."""
    width = obj.size[0] if obj.shape == "box" else 2.0 * obj.size[0]
    timing = {"settle_frames": 2, "squeeze_frames": 12, "lift_frames": 2}
    timing["turn_frames"] = 30 if turn else 0
    timing["slide_frames"] = 15 if any(slide) else 0
    timing.update(frames)
    script = two_finger_pinch(
        obj.position,
        gap=width + 2 * CLEARANCE,
        finger_radius=FINGER_RADIUS,
        approach=CLEARANCE + depth,
        turn=turn,
        slide=slide,
        **timing,
    )
    return scripted(name, config, script, extra_frames=5, noise=noise, seed=3)


def pinch_box(name: str = "pinch", obj: ObjectConfig | None = None, **sections: Any) -> Case:
    """:func:`pinch` of the box (or ``obj``) on the small table with scene overrides."""
    obj = box() if obj is None else obj
    return pinch(obj, scene(obj, **sections), name)


def merge_split() -> Case:
    """A pinch whose two right-hand fingertips merge into one contact while they
    squeeze, turn the box 45° merged, then split apart again."""
    gap = 0.06 + 2 * CLEARANCE
    side = 0.5 * gap + FINGER_RADIUS
    hand = Hand()
    hand.add("thumb", Fingertip((-side, 0.0), radii=_TIP), touching=False)
    # 24 mm apart with 16 mm tips: they touch after moving 4 mm each.
    hand.add("index", Fingertip((side, 0.012), radii=_TIP), touching=False)
    hand.add("middle", Fingertip((side, -0.012), radii=_TIP), touching=False)
    names = ("thumb", "index", "middle")
    squeeze = CLEARANCE + 0.003
    phases = [
        _down(names),
        Phase(
            10,
            {
                "thumb": FingerMotion(translation=(squeeze, 0.0)),
                "index": FingerMotion(translation=(-squeeze, 0.0)),
                "middle": FingerMotion(translation=(-squeeze, 0.0)),
            },
            name="squeeze",
        ),
        Phase(
            10,
            {
                "index": FingerMotion(translation=(0.0, -0.007)),
                "middle": FingerMotion(translation=(0.0, 0.007)),
            },
            name="merge",
        ),
        Phase(15, group=GroupMotion(names, rotation=math.pi / 4), name="turn"),
        Phase(
            10,
            {
                "index": FingerMotion(translation=(0.0, 0.008)),
                "middle": FingerMotion(translation=(0.0, -0.008)),
            },
            name="split",
        ),
        _up(names),
    ]
    return scripted("merge and split", scene(box()), Script(hand, phases), 5)


def deep_release(depth: float = 0.02, mass: float = 0.1) -> Case:
    """Squeeze ``depth`` into a box from both sides, hold, lift the index finger,
    then the thumb: the thumb's particles spring back by up to ``depth``."""
    script = release(
        (0.0, 0.0),
        gap=0.06 + 2 * CLEARANCE,
        finger_radius=FINGER_RADIUS,
        approach=CLEARANCE + depth,
        settle_frames=2,
        squeeze_frames=20,
        hold_frames=5,
        stagger_frames=10,
        lift_frames=2,
    )
    name = f"release after a {1000 * depth:g} mm squeeze"
    return scripted(name, scene(box(mass=mass)), script, extra_frames=5)


# -- strikes and rubs --------------------------------------------------------------


def strike(speed: float, fps: float = 60.0, mass: float = 0.2, travel: float = 0.12) -> Case:
    """A fingertip driven at ``speed`` into the box's side and on through it.

    It touches down 5 mm short of the face and travels ``travel`` (12 cm: past the
    far face). The match radius is raised so the tracker follows it at 5 m/s.
    """
    frames = max(1, round(travel / speed * fps))
    config = scene(box(mass=mass), surface={"fps": fps}, contacts={"match_radius": 0.1})
    script = side_strike(
        (-0.03, 0.0),
        0.0,
        FINGER_RADIUS,
        clearance=0.005,
        depth=travel - 0.005,
        settle_frames=2,
        strike_frames=frames,
        lift_frames=2,
    )
    return scripted(f"strike at {speed:g} m/s, {fps:g} fps", config, script, extra_frames=5)


def inside_footprint() -> Case:
    """Fingertips that touch down on the box's top, across its side and just inside
    it, then move 3 cm across it."""
    hand = Hand()
    hand.add("top", Fingertip((0.0, 0.0), radii=_TIP), touching=False)
    hand.add("across", Fingertip((-0.03, 0.015), radii=_TIP), touching=False)
    hand.add("inside", Fingertip((0.025, -0.015), radii=_TIP), touching=False)
    names = hand.names
    phases = [
        _down(names, 3),
        Phase(20, {n: FingerMotion(translation=(0.03, 0.0)) for n in names}, name="move"),
        _up(names),
    ]
    return scripted("inside footprint", scene(box()), Script(hand, phases), 5)


def flat_hand() -> Case:
    """A flat hand laid over three small objects, slid 6 cm while turning, lifted."""
    objects = [
        ObjectConfig(
            name="cube", shape="box", size=(0.02, 0.02, 0.02), mass=0.02, position=(-0.02, 0.01)
        ),
        ObjectConfig(name="ball", shape="sphere", size=(0.01,), mass=0.01, position=(0.02, 0.015)),
        ObjectConfig(
            name="can", shape="cylinder", size=(0.012, 0.02), mass=0.02, position=(0.0, -0.025)
        ),
    ]
    hand = Hand()
    hand.add("palm", Palm((0.0, 0.0), size=(0.1, 0.09), corner_radius=0.02), touching=False)
    phases = [
        _down(["palm"]),
        Phase(25, {"palm": FingerMotion(translation=(0.06, 0.0), rotation=0.3)}, name="slide"),
        _up(["palm"]),
    ]
    return scripted("flat hand", scene(*objects), Script(hand, phases), 5)


def off_the_edge() -> Case:
    """A box and a tall can near the table's right edge pushed off it; they fall
    0.75 m to the floor."""
    edge = TABLE_SIZE[0] / 2
    objects = [
        box(position=(edge - 0.04, 0.04)),
        ObjectConfig(
            name="can",
            shape="cylinder",
            size=(0.015, 0.05),
            mass=0.05,
            position=(edge - 0.03, -0.05),
        ),
    ]
    hand = Hand()
    hand.add("box pusher", Fingertip((edge - 0.085, 0.04), radii=_TIP), touching=False)
    hand.add("can pusher", Fingertip((edge - 0.06, -0.05), radii=_TIP), touching=False)
    names = hand.names
    phases = [
        _down(names),
        Phase(15, {n: FingerMotion(translation=(0.07, 0.0)) for n in names}, name="push"),
        _up(names),
    ]
    # 35 empty frames: the fall takes about 24.
    return scripted("off the edge", scene(*objects), Script(hand, phases), 35)


# -- what the camera sees ----------------------------------------------------------


def single_pixels() -> Case:
    """Single-pixel contacts: still ones on the box's top, on its edges and beside
    its sides; one that presses into its side a pixel a frame; others that flicker
    on and off at random around it. The table's smallest-contact filter is off:
    single pixels are what this case is about."""
    config = scene(box(), contacts={"min_area": 0.0})
    surface = Surface.from_config(config.surface)
    still = surface.world_to_pixel(
        np.array([[0.0, 0.0], [0.02, 0.01], [-0.031, 0.0], [0.0, 0.0305], [0.031, -0.02]])
    )
    start = surface.world_to_pixel(np.array([[-0.04, -0.01]]))
    rng = np.random.default_rng(7)
    frames = 40
    flicker_at = surface.world_to_pixel(rng.uniform(-0.04, 0.04, size=(12, 2)))
    flicker_on = rng.integers(0, 2, size=(frames, len(flicker_at))).astype(bool)

    def masks(surface: Surface) -> list[Mask]:
        out = []
        for frame in range(frames):
            moving = start + np.array([frame, 0.0])
            pixels = np.concatenate([still, moving, flicker_at[flicker_on[frame]]])
            cols, rows = np.round(pixels).astype(np.int64).T
            mask = np.zeros(surface.shape, np.uint8)
            mask[rows, cols] = 255
            out.append(mask)
        return out

    # The moving pixel crosses a pixel a frame; the others stand still.
    speed = float(surface.pixel_size.max()) * surface.fps
    return Case("single pixels", config, masks, speed)


def border() -> Case:
    """Contacts on the image border: single pixels in the corners and mid-edge that
    blink, a fingertip half off the table sliding along its left edge into a box
    lying there, and one in the corner; both then leave the image. Single pixels
    need the smallest-contact filter off."""
    half_w, half_h = TABLE_SIZE[0] / 2, TABLE_SIZE[1] / 2
    config = scene(box(position=(-half_w + 0.035, 0.0)), contacts={"min_area": 0.0})
    surface = Surface.from_config(config.surface)
    width, height = surface.resolution
    corners = np.array([[0, 0], [width - 1, 0], [0, height - 1], [width - 1, height - 1]])
    edges = np.array([[width // 2, 0], [width - 1, height // 2]])
    blinking = np.concatenate([corners, edges])
    hand = Hand()
    hand.add("edge", Fingertip((-half_w, -0.07), radii=_TIP), touching=False)
    hand.add("corner", Fingertip((half_w, half_h), radii=_TIP), touching=False)
    phases = [
        _down(hand.names),
        Phase(20, {"edge": FingerMotion(translation=(0.0, 0.08))}, name="push"),
        Phase(
            10,
            {
                "edge": FingerMotion(translation=(-0.02, 0.0)),
                "corner": FingerMotion(translation=(0.02, 0.02)),
            },
            name="leave",
        ),
        Phase(3, name="gone"),
    ]
    hands = [hand for _, hand in Script(hand, phases).frames(surface)]

    def masks(surface: Surface) -> list[Mask]:
        out = []
        for frame, shown in enumerate(hands):
            mask = render_mask(shown, surface)
            if frame % 3:
                mask[blinking[:, 1], blinking[:, 0]] = 255
            out.append(mask)
        return out

    return Case("border", config, masks, hand_speed(hands))


#: A noisy table: blurred, wobbling edges, holes, a few flipped pixels per frame.
NOISE = SensorNoise(blur_sigma=0.7, salt_pepper=2e-5, holes=3, hole_radius=2.5, jitter=1.0)


def noisy(min_area: float | None = None) -> Case:
    """The pinch of the box seen through :data:`NOISE`; ``min_area`` overrides the
    smallest-contact filter (``contacts.min_area``)."""
    obj = box()
    sections = {} if min_area is None else {"contacts": {"min_area": min_area}}
    return pinch(obj, scene(obj, **sections), "noisy masks", noise=NOISE)


# -- random fingers (the property test) ----------------------------------------------


def random_fingers(paths: Sequence[FingerPath], frames: int, obj: ObjectConfig) -> Case:
    """Fingertips on :class:`FingerPath` s around an object for ``frames`` frames,
    then 3 empty frames (default settings on the small table)."""
    config = scene(obj)
    hands = finger_hands(paths, frames, 1.0 / config.surface.fps)
    return played("random fingers", config, hands, extra_frames=3)


#: Three fingers found by a random search over the property test's motions, before
#: its domain was narrowed: the thin one (0.77 m/s) shoves the box into a wide one
#: that drifts the other way at 0.14 m/s.
SHOVE_INTO_A_FINGER = (
    FingerPath((0.0589, -0.0152), (0.1067, -0.1971), 0.01068, down=0, up=28),
    FingerPath((-0.0035, 0.0512), (-0.1326, 0.0566), 0.01097, down=1, up=23),
    FingerPath((-0.0053, -0.0714), (-0.2606, 0.7259), 0.00478, down=2, up=6),
)
