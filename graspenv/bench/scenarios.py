"""The bench's scenarios: scripted hands with ground truth to measure against.

Each scenario plays a scripted synthetic hand through the whole pipeline
(:func:`~graspenv.bench.playback.play`) and measures what it did against ground
truth (docs/design.md, "How we measure"):

- ``turn``: two fingertips squeeze a 6 cm box and turn 90° in place (the canonical
  scene). Ideal rigid grasp: the box turns with the fingers about its own centre.
  Errors: yaw (degrees) and centre drift (mm).
- ``slide``: the same grasp slides 10 cm. Error: travel against the fingers' (mm).
- ``slip``: the box is squeezed and held while a side force grows by
  :data:`SLIP_RATE` N/s until it slips (slides at :data:`SLIP_SPEED` from under every
  gripping particle). Coulomb's prediction from the
  measured normal forces: ``μ_f·ΣN_fingers + μ_t·N_table`` with the products of the
  friction coefficients Bullet uses. Error: relative (%).
- ``flick``: a fingertip strikes the box's side at 0.25 m/s and lifts. No closed form:
  error is the drift against the reference-fidelity run (mm).
- ``two hands``: ten fingertips, five per hand, each hand squeezing a box and
  carrying it 8 cm, the hands in opposite directions. Error: travel (mm).
- ``noisy``: the turn, with blurred, jittered masks with holes (seeded). Error: yaw.

Every scenario takes a placement offset (:func:`placement_offsets`): the whole scene
shifted by a fraction of a pixel (:mod:`graspenv.bench.frontier` says why).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Protocol

import numpy as np

from graspenv.bench.interactions import BOX, CLEARANCE, FINGER_RADIUS, pinch, with_objects
from graspenv.bench.playback import Played, play
from graspenv.config import ObjectConfig, SceneConfig
from graspenv.geometry import tilt_angle
from graspenv.physics import ContactReport, PhysicsWorld
from graspenv.simulation import Simulation
from graspenv.surface.hand import Hand
from graspenv.surface.noise import SensorNoise
from graspenv.surface.scripts import FingerMotion, Phase, Script, side_strike
from graspenv.surface.shapes import Fingertip
from graspenv.tasks.metrics import coulomb_slip_force

__all__ = [
    "CREEP_DISTANCE",
    "DEPTH",
    "FLAT_BOX",
    "NOISE",
    "SCENARIOS",
    "SLIP_FRAMES",
    "SLIP_RATE",
    "SLIP_SPEED",
    "Offset",
    "Scenario",
    "flick",
    "noisy",
    "normal_tilt_push",
    "placement_offsets",
    "push_until_slip",
    "slide",
    "slip",
    "turn",
    "turn_scene",
    "two_hands",
    "two_hands_scene",
]

DEPTH = 0.003  # how far each fingertip is pressed into a gripped box, metres
SLIP_RATE = 6.0  # newtons per second
SLIP_FRAMES = 900  # the ramp gives up at SLIP_RATE × 15 s = 90 N (the figure is then NaN)
#: The box slips when it slides this fast from under every particle gripping it (the
#: slowest of them), m/s: Coulomb's limit for the whole grip is gross slip, when no
#: contact holds. Before that it creeps: under a growing push the particles with the
#: least normal force slide first while the others hold it, and it moves with their
#: give. Past the limit the excess force accelerates it: on the 0.2 kg box at 6 N/s it
#: reaches 10 mm/s within two frames, 1 % of the force later (docs/speed.md, "Speed against
#: error"). Measured against the grip's mean instead (until 2026-12-06), a cylinder
#: held at last by the two most pressed particles of each fingertip's arc crept past
#: this speed 4-10 % short of Coulomb's force (docs/accuracy.md, "Accuracy across the grasp
#: space"). The grip's mean creeping 0.5 mm is reported too.
SLIP_SPEED = 0.01
#: The slip's onset: of the frames up to and including the gross slip, the first
#: of the run that slid at least this fast from under every particle, m/s. Before
#: the slip the slowest particle's slide is under 0.1 mm/s on the bench's flat box,
#: and its onset frame a few mm/s; the gross slip at :data:`SLIP_SPEED` comes a frame or
#: two later, which puts the slip force that many steps of the push late
#: (``slip_onset_*`` in :func:`push_until_slip`).
SLIP_ONSET_SPEED = 0.001
CREEP_DISTANCE = 0.0005  # metres of creep reported as ``creep_force_n``


#: A scene shift, metres (x, y): every object and finger moves by it.
Offset = tuple[float, float]


def _shifted(config: ObjectConfig, offset: Offset) -> ObjectConfig:
    x, y = config.position
    return replace(config, position=(x + offset[0], y + offset[1]))


def placement_offsets(count: int, scene: SceneConfig) -> list[Offset]:
    """``count`` sub-pixel scene shifts, the first (0, 0), the others spread over the
    pixel by the golden-ratio sequence (a different phase in x and y)."""
    (width, depth), (columns, rows) = scene.surface.size, scene.surface.resolution
    pixel_x, pixel_y = width / columns, depth / rows
    golden = (math.sqrt(5.0) - 1.0) / 2.0
    return [
        (pixel_x * ((k * golden) % 1.0), pixel_y * ((k * golden * golden + 0.5 * (k > 0)) % 1.0))
        for k in range(count)
    ]


def turn_scene(base: SceneConfig, offset: Offset = (0.0, 0.0)) -> tuple[SceneConfig, Script]:
    """The canonical scene: two fingertips squeeze the 6 cm box and turn it 90° in
    place (90 frames), then hold (15 frames)."""
    box = _shifted(BOX, offset)
    script = pinch(box, DEPTH, turn=math.pi / 2, turn_frames=90, slide_frames=0, hold_frames=15)
    return with_objects(base, box), script


def turn(
    base: SceneConfig,
    offset: Offset = (0.0, 0.0),
    noise: SensorNoise | None = None,
    replays: int = 1,
) -> Played:
    scene, script = turn_scene(base, offset)
    played = play(scene, script, ["box"], ("turn", "hold"), noise, replays=replays)
    x, y, _, yaw = played.final["box"]
    played.errors["yaw_error_deg"] = math.degrees(math.remainder(yaw - math.pi / 2, 2 * math.pi))
    played.errors["drift_mm"] = 1000 * math.hypot(x - offset[0], y - offset[1])
    return played


def slide(base: SceneConfig, offset: Offset = (0.0, 0.0), replays: int = 1) -> Played:
    box = _shifted(BOX, offset)
    script = pinch(box, DEPTH, slide=(0.0, 0.10), turn_frames=0, slide_frames=90, hold_frames=15)
    played = play(with_objects(base, box), script, ["box"], ("slide", "hold"), replays=replays)
    x, y, _, yaw = played.final["box"]
    played.errors["travel_error_mm"] = 1000 * math.hypot(x - offset[0], y - offset[1] - 0.10)
    played.errors["yaw_drift_deg"] = math.degrees(yaw)
    return played


#: The slip scenario's box is flat, so that the side force (applied at its centre of
#: mass, 4 mm up) cannot tip it over the grip's contacts (2 mm up) before it slips.
FLAT_BOX = ObjectConfig(name="box", shape="box", size=(0.06, 0.06, 0.008), mass=0.2)


def slip(base: SceneConfig, offset: Offset = (0.0, 0.0), replays: int = 1) -> Played:
    """Squeeze a flat box lightly, settle, then push it along +y (across the grip)
    with a force growing by :data:`SLIP_RATE` N/s until it slips (:func:`push_until_slip`).
    Timed once: the push acts from inside the run (``replays`` is not used)."""
    del replays
    return push_until_slip(base, _shifted(FLAT_BOX, offset), 0.001)


def push_until_slip(
    base: SceneConfig,
    obj: ObjectConfig,
    depth: float,
    *,
    rate: float = SLIP_RATE,
    relative_rate: float | None = None,
    ramp_frames: int = SLIP_FRAMES,
    height: float | None = None,
    finger_radius: float = FINGER_RADIUS,
) -> Played:
    """Squeeze ``obj`` (its name must be "box") ``depth`` deep, settle 20 frames, then
    push it along +y (across the grip) with a growing force until it slips: slides at
    :data:`SLIP_SPEED` from under every particle gripping it (before, they give
    elastically with it, and the least pressed slide while the others hold).

    Args:
        base: the scene whose settings are under test.
        obj: the gripped object.
        depth: how far each fingertip presses into it, metres.
        rate: the push's growth, N/s.
        relative_rate: instead, its growth as a share of Coulomb's prediction (from
            the normal forces measured while settling) a second.
        ramp_frames: frames of the ramp before it gives up (the figure is then NaN).
        height: the push's line of action passes this far above the table (metres);
            ``None``: through the centre of mass.
        finger_radius: fingertip radius, metres.

    Returns:
        The run, with errors ``slip_force_n``, ``coulomb_force_n``,
        ``slip_error_pct``, ``creep_force_n``, ``grip_normal_n`` (settled),
        ``tilt_at_slip_deg``, ``grip_normal_spread_pct`` (the settled normal
        force's standard deviation over its mean, per cent, frame to frame: a
        grip that jitters, as one of many sub-steps at a per-step contact ERP
        does, spreads), and ``slip_normal_n`` and ``slip_error_then_pct``:
        the fingers' normal force over the five frames before the slip, and the
        slip against Coulomb's force from it; ``slip_onset_force_n``,
        ``slip_onset_error_pct`` and ``slip_onset_then_pct``: the same at the
        slip's onset (:data:`SLIP_ONSET_SPEED`), the push midway between the last
        one held and the first not held; ``slip_normal_tilt_pct``: over the same
        five frames, how much further than Coulomb's force Bullet's contact normals
        hold the object against the push (:func:`normal_tilt_push`), per cent of
        Coulomb's force (not an error of the model: the engine's; round a
        cylinder's side Bullet finds the normal only to a few degrees).
    """
    settle = 20
    script = pinch(
        obj,
        depth,
        finger_radius=finger_radius,
        turn_frames=0,
        slide_frames=0,
        hold_frames=settle + ramp_frames,
    )
    scene = with_objects(base, obj)
    hold_start = sum(
        len(frames) for name, frames in script.phase_ranges() if name in ("touch", "squeeze")
    )
    ramp_start = hold_start + settle
    dt = 1.0 / scene.surface.fps
    # Bullet's combined friction is the product of the two bodies' coefficients.
    finger_mu = base.proxy.particle_friction * obj.friction
    table_mu = base.physics.table_friction * obj.friction

    def predicted(normal: float | None = None) -> float:
        # Mean normal forces (newtons, the last sub-step of each frame) while settled,
        # or the fingers' ``normal`` given; each finger presses with about half. A
        # finger's is the resultant of its particles' (ContactReport.grip_normal_force).
        normal = float(np.mean(state["normal"])) if normal is None else normal
        table = float(np.mean(state["table"]))
        return coulomb_slip_force(normal / 2, finger_mu) + table_mu * table

    state: dict[str, Any] = {
        "normal": [], "table": [], "ramp_normal": [], "ramp_tilt": [], "start": None,
        "force": math.nan, "creep": math.nan, "rate": rate, "speeds": [],
    }  # fmt: skip

    def each(sim: Simulation, index: int, played: Played) -> bool:
        if hold_start <= index:
            report = sim.contact_report("box")
            fingers = report.grip_normal_force(sim.particles_by_contact())
            if index < ramp_start:
                table = (report.particle < 0) & (report.other_object < 0)
                state["normal"].append(float(fingers))
                state["table"].append(float(report.normal_force[table].sum()))
        if index + 1 >= ramp_start:
            states = sim.world.object_states()
            row = sim.world.object_index("box")
            position = states.position[row]
            rotation = states.rotation[row].reshape(3, 3)
            if state["start"] is None:  # this frame's ``report`` is the settled grip's
                ids = np.unique(report.particle[report.particle >= 0])
                if ids.size == 0:  # no particle grips it (rigid proxies): no figure
                    return True
                state["ids"] = ids
                state["start"] = True
                # The box's own points under each gripping particle: a tall box rocks
                # about the grip's line, which moves its centre but slides nothing.
                state["local"] = (sim.world.pool.positions(ids) - position) @ rotation
                state["apart"] = np.zeros((ids.size, 2))
                if relative_rate is not None:
                    state["rate"] = relative_rate * predicted()
            force = state["rate"] * (index + 1 - ramp_start) * dt
            # How far the box has slid from under each particle, and the grip's mean.
            apart = (
                position + state["local"] @ rotation.T - sim.world.pool.positions(state["ids"])
            )[:, :2]
            moved = float(np.linalg.norm(apart.mean(axis=0)))
            if moved > CREEP_DISTANCE and math.isnan(state["creep"]):
                state["creep"] = force
            # It slips when it slides from under every particle: while one holds, it
            # creeps with that particle's give (partial slip, module docstring).
            speed = float(np.linalg.norm(apart - state["apart"], axis=1).min()) / dt
            state["apart"] = apart
            state["speeds"].append(speed)
            if speed > SLIP_SPEED:
                state["force"] = force
                state["tilt"] = math.degrees(tilt_angle(sim.object_pose("box")[1]))
                return True
            state["ramp_normal"].append(float(fingers))
            state["ramp_tilt"].append(normal_tilt_push(sim.world, report, (0.0, 1.0)))
            push = state["rate"] * (index + 2 - ramp_start) * dt
            sim.apply_force("box", (0.0, push, 0.0), height)
        return False

    played = play(scene, script, ["box"], (), each_frame=each)
    coulomb = predicted()

    def against(force: float, frame: int) -> tuple[float, float, float]:
        # ``force`` against Coulomb's at the settled normal force and at the grip's
        # normal force over the five frames before ``frame`` of the ramp (not the
        # slip's own, whose contacts are breaking), and that normal force.
        normal = state["ramp_normal"][max(0, frame - 5) : frame]
        if not normal:
            return _percent(force, coulomb), math.nan, math.nan
        then = float(np.mean(normal))
        return _percent(force, coulomb), _percent(force, predicted(then)), then

    errors = played.errors
    errors["grip_normal_n"] = float(np.mean(state["normal"]))
    # How steady the settled grip is: its normal force's spread over those frames.
    errors["grip_normal_spread_pct"] = _spread_pct(state["normal"])
    errors["tilt_at_slip_deg"] = state.get("tilt", math.nan)
    errors["slip_force_n"] = state["force"]
    errors["coulomb_force_n"] = coulomb
    # No figure where no particle gripped it (rigid proxies) or it never slipped.
    nan = math.nan
    errors.update(
        slip_error_pct=nan, creep_force_n=state["creep"], slip_normal_n=nan,
        slip_error_then_pct=nan, slip_onset_force_n=nan, slip_onset_error_pct=nan,
        slip_onset_then_pct=nan, slip_normal_tilt_pct=nan,
    )  # fmt: skip
    if math.isfinite(state["force"]):
        # Coulomb's law at the normal force the grip had just before the slip too:
        # the grip gives before it slips, and round a curved side that costs
        # normal force. The last frame of the ramp is the slip's.
        figures = against(state["force"], len(state["speeds"]) - 1)
        errors["slip_error_pct"], errors["slip_error_then_pct"], errors["slip_normal_n"] = figures
        last = len(state["speeds"]) - 1
        tilt = state["ramp_tilt"][max(0, last - 5) : last]
        if tilt:
            # The push they add against the slip is along -y.
            errors["slip_normal_tilt_pct"] = -100.0 * float(np.mean(tilt)) / coulomb
        # The frames count from the ramp's start: frame k's slide is under the push
        # of rate·k·dt (zero in the first), so the last push held is frame - 1's.
        frame = _onset(state["speeds"])
        onset = state["rate"] * (frame - 0.5) * dt
        errors["slip_onset_force_n"] = onset
        errors["slip_onset_error_pct"], errors["slip_onset_then_pct"], _ = against(onset, frame)
    return played


def _spread_pct(values: Sequence[float]) -> float:
    """The standard deviation of ``values`` as a share of their mean, per cent (NaN
    for none, or a mean of zero)."""
    mean = float(np.mean(values)) if len(values) else 0.0
    return 100.0 * float(np.std(values)) / mean if mean else math.nan


def normal_tilt_push(world: PhysicsWorld, report: ContactReport, along: Sequence[float]) -> float:
    """The force along ``along`` (a unit vector in the table plane) that the tilt of
    Bullet's contact normals adds to the particles' push on an object's sides:
    Σ N·(Bullet's normal − the side's exact one)·along over the particles' contacts
    on a side, newtons (the exact normal is the footprint's:
    :meth:`~graspenv.physics.world.PhysicsWorld.footprint_side`). A normal α off
    turns N·sin α of its contact's push along the side, α/μ of the friction there;
    against a box's face Bullet's normal is exact, against a cylinder's side off by
    up to about 4° (``tests/physics/test_physics_world.py``).

    Args:
        world: the world the report is from.
        report: one object's contacts (:meth:`~graspenv.physics.world.PhysicsWorld.contact_report`).
        along: the direction, (2,).
    """
    pressing = report.particle >= 0
    _, _, outward = world.footprint_side(report.position[pressing, :2], 2.0 * world.pool.radius)
    sided = np.any(outward != 0.0, axis=1)
    # Both normals point into the object, the way the contact pushes it.
    tilt = report.normal[pressing][sided, :2] + outward[sided]
    return float(report.normal_force[pressing][sided] @ (tilt @ np.asarray(along, dtype=float)))


def _percent(force: float, reference: float) -> float:
    """``force`` against ``reference``, per cent."""
    return 100 * (force - reference) / reference


def _onset(speeds: list[float]) -> int:
    """The frame that began the run of frames sliding at least
    :data:`SLIP_ONSET_SPEED` which ends in the slip.

    Args:
        speeds: the slowest particle's slide each frame of the ramp, m/s, the last
            the gross slip's frame.

    Returns:
        The index of that frame in ``speeds`` (at least 1: the ramp's first frame
        has no push).
    """
    frame = len(speeds) - 1
    while frame > 0 and speeds[frame - 1] >= SLIP_ONSET_SPEED:
        frame -= 1
    return frame


def flick(base: SceneConfig, offset: Offset = (0.0, 0.0), replays: int = 1) -> Played:
    box = _shifted(BOX, offset)
    script = side_strike(
        (offset[0] - 0.03, offset[1]),
        0.0,
        FINGER_RADIUS,
        clearance=0.01,
        depth=0.01,
        strike_frames=5,
    )
    return play(
        with_objects(base, box), script, ["box"], ("strike",), extra_frames=40, replays=replays
    )


def _five_finger_hand(hand: Hand, prefix: str, centre: tuple[float, float], half: float) -> None:
    """Five lifted fingertips around a box: two on each side face, one below."""
    gap = half + CLEARANCE + FINGER_RADIUS
    cx, cy = centre
    spots = [(-gap, -0.015), (-gap, 0.015), (gap, -0.015), (gap, 0.015), (0.0, -gap)]
    for k, (dx, dy) in enumerate(spots):
        tip = Fingertip((cx + dx, cy + dy), 0.0, radii=(FINGER_RADIUS, FINGER_RADIUS))
        hand.add(f"{prefix}{k}", tip, touching=False)


def two_hands_scene(
    base: SceneConfig, offset: Offset = (0.0, 0.0)
) -> tuple[SceneConfig, Script, ObjectConfig, ObjectConfig]:
    """Ten fingertips, five per hand: each hand squeezes its own box and carries it
    8 cm, the hands in opposite directions. Returns the scene, the script and the
    left and right boxes."""
    left, right = (
        _shifted(replace(BOX, name=name, position=(x, 0.0)), offset)
        for name, x in (("left", -0.1), ("right", 0.1))
    )
    hand = Hand()
    _five_finger_hand(hand, "l", left.position, 0.03)
    _five_finger_hand(hand, "r", right.position, 0.03)
    names = [name for name, _shape, _down in hand]
    squeeze = {}
    for name in names:
        centre = left.position if name.startswith("l") else right.position
        inward = np.asarray(centre) - hand[name].centre
        inward *= (CLEARANCE + DEPTH) / np.linalg.norm(inward)
        squeeze[name] = FingerMotion(
            touching=True, translation=(float(inward[0]), float(inward[1]))
        )
    carry = {
        name: FingerMotion(
            touching=True, translation=(0.0, 0.08 if name.startswith("l") else -0.08)
        )
        for name in names
    }
    script = Script(
        hand,
        [
            Phase(5, {n: FingerMotion(touching=True) for n in names}, name="touch"),
            Phase(20, squeeze, name="squeeze"),
            Phase(90, carry, name="carry"),
            Phase(15, {n: FingerMotion(touching=True) for n in names}, name="hold"),
        ],
    )
    return with_objects(base, left, right), script, left, right


def two_hands(base: SceneConfig, offset: Offset = (0.0, 0.0), replays: int = 1) -> Played:
    """Ten fingertips: each hand squeezes its own box and carries it 8 cm."""
    scene, script, left, right = two_hands_scene(base, offset)
    played = play(scene, script, ["left", "right"], ("carry", "hold"), replays=replays)
    # The left box is carried 8 cm along +y, the right one along -y.
    errors = [
        math.hypot(*(played.final[box.name][:2] - (box.position[0], box.position[1] + carry_y)))
        for box, carry_y in ((left, 0.08), (right, -0.08))
    ]
    played.errors["travel_error_mm"] = 1000 * max(errors)
    return played


NOISE = SensorNoise(blur_sigma=1.0, holes=2, hole_radius=2.0, jitter=0.7, jitter_scale=6.0)


def noisy(base: SceneConfig, offset: Offset = (0.0, 0.0), replays: int = 1) -> Played:
    return turn(base, offset, NOISE, replays)


class Scenario(Protocol):
    """A scenario: (scene, placement offset, timing replays) → what it measured."""

    def __call__(
        self, base: SceneConfig, offset: Offset = ..., *, replays: int = ...
    ) -> Played: ...


#: name → scenario; each returns a :class:`Played` with its ground-truth errors.
SCENARIOS: dict[str, Scenario] = {
    "turn": turn,
    "slide": slide,
    "slip": slip,
    "flick": flick,
    "two hands": two_hands,
    "noisy": noisy,
}
