"""``graspenv bench --fuzz N``: random hard episodes, the stability invariants checked
on every frame.

Each episode is drawn from its own seed, so any one can be played again alone
(:func:`episode`). It holds, on a 32 × 24 cm table seen at 320 × 240 pixels:

- an object (a box, an upright cylinder or a ball; a second one in about a tenth of
  the episodes), 3–10 cm across and 1–8 cm high, of mass 5 g–5 kg (log-uniform) and
  friction 0–2, on a table of friction 0–2;
- one to six fingertips (radius 3–12 mm) on straight paths around them, each
  touching down and lifting at random frames; a third of them fast (0.5–5 m/s),
  the others up to 0.5 m/s; a pair of fingertips that cross paths in a third of
  the episodes (their contacts merge, then split);
- in half of them, sensor noise (:class:`graspenv.surface.SensorNoise`) at a random
  level up to a blur of 1.5 pixels, edge jitter of 2 pixels, four holes of up to 4
  pixels and 5 flipped pixels in 100 000.

The invariants are :mod:`graspenv.bench.invariants`' (finite state, objects above
the table and not tunnelling, particles out of objects, object speeds within the
bound the fingers allow), at the default settings or at a fidelity preset
(``--preset``), over a scene file's settings (``--config``; the episodes' objects and
table stay their own).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from graspenv.bench.invariants import InvariantChecker, Tolerances, hand_speed
from graspenv.bench.jobs import run_jobs
from graspenv.bench.results import write_rows
from graspenv.config import (
    ObjectConfig,
    SceneConfig,
    at_fidelity,
    load_config,
    resolve_fidelity,
    to_dict,
)
from graspenv.simulation import Simulation
from graspenv.surface import Fingertip, Hand, SensorNoise, render_mask

__all__ = [
    "Episode",
    "FingerPath",
    "FuzzReport",
    "Outcome",
    "episode",
    "finger_hands",
    "play",
    "run_fuzz",
]

TABLE_SIZE = (0.32, 0.24)
TABLE_PIXELS = (320, 240)
FRAMES = 30  # frames with fingers, then EMPTY_FRAMES without
EMPTY_FRAMES = 3
MAX_SPEED = 5.0  # m/s


@dataclass(frozen=True)
class FingerPath:
    """A fingertip on a straight line at constant speed.

    Attributes:
        start: centre at frame 0, metres, (x, y).
        velocity: m/s, (x, y).
        radius: metres.
        down: first frame it touches the table.
        up: first frame it is lifted again (past the last frame: never).
    """

    start: tuple[float, float]
    velocity: tuple[float, float]
    radius: float
    down: int
    up: int


def finger_hands(paths: Sequence[FingerPath], frames: int, dt: float) -> list[Hand]:
    """The hand of each of ``frames`` frames ``dt`` seconds apart, a fingertip on
    each path (named ``finger <i>``)."""
    out = []
    for frame in range(frames):
        hand = Hand()
        for i, path in enumerate(paths):
            centre = np.asarray(path.start) + frame * dt * np.asarray(path.velocity)
            tip = Fingertip(centre, radii=(path.radius, path.radius), linear_velocity=path.velocity)
            hand.add(f"finger {i}", tip, touching=path.down <= frame < path.up)
        out.append(hand)
    return out


@dataclass(frozen=True)
class Episode:
    """One random episode (see the module docstring)."""

    seed: int
    scene: SceneConfig
    fingers: tuple[FingerPath, ...]
    noise: SensorNoise | None

    def hands(self) -> list[Hand]:
        return finger_hands(self.fingers, FRAMES, 1.0 / self.scene.surface.fps)

    def describe(self) -> str:
        objects = ", ".join(
            f"{o.shape} {1000 * o.mass:.3g} g mu {o.friction:.2f}" for o in self.scene.objects
        )
        fastest = max(math.hypot(*p.velocity) for p in self.fingers)
        noise = "noisy" if self.noise is not None else "clean"
        return (
            f"{objects}; table mu {self.scene.physics.table_friction:.2f}; "
            f"{len(self.fingers)} fingers up to {fastest:.2f} m/s; {noise}"
        )


def _object(rng: np.random.Generator, name: str, position: tuple[float, float]) -> ObjectConfig:
    shape = str(rng.choice(["box", "box", "cylinder", "sphere"]))
    across = float(rng.uniform(0.03, 0.10))
    height = float(rng.uniform(0.01, 0.08))
    size: tuple[float, ...] = {
        "box": (across, float(rng.uniform(0.03, 0.10)), height),
        "cylinder": (across / 2, height),
        "sphere": (across / 2,),
    }[shape]
    return ObjectConfig(
        name=name,
        shape=shape,  # type: ignore[arg-type]
        size=size,
        mass=float(math.exp(rng.uniform(math.log(0.005), math.log(5.0)))),
        friction=float(rng.uniform(0.0, 2.0)),
        position=position,
        yaw=float(rng.uniform(-math.pi, math.pi)),
    )


def _finger(rng: np.random.Generator, near: tuple[float, float]) -> FingerPath:
    fast = rng.random() < 1.0 / 3.0
    speed = float(rng.uniform(0.5, MAX_SPEED) if fast else rng.uniform(0.0, 0.5))
    heading = float(rng.uniform(0.0, 2.0 * math.pi))
    start = (near[0] + float(rng.uniform(-0.08, 0.08)), near[1] + float(rng.uniform(-0.08, 0.08)))
    down = int(rng.integers(0, FRAMES // 2))
    return FingerPath(
        start,
        (speed * math.cos(heading), speed * math.sin(heading)),
        float(rng.uniform(0.003, 0.012)),
        down,
        int(rng.integers(down + 1, FRAMES + 4)),
    )


def _crossing_pair(
    rng: np.random.Generator, near: tuple[float, float]
) -> tuple[FingerPath, FingerPath]:
    """Two fingertips that meet halfway through the episode and part again."""
    meet = (near[0] + float(rng.uniform(-0.04, 0.04)), near[1] + float(rng.uniform(-0.04, 0.04)))
    speed = float(rng.uniform(0.05, 0.4))
    heading = float(rng.uniform(0.0, math.pi))
    t = (FRAMES / 2) / 60.0
    pair = []
    for sign in (1.0, -1.0):
        v = (sign * speed * math.cos(heading), sign * speed * math.sin(heading))
        start = (meet[0] - v[0] * t, meet[1] - v[1] * t)
        pair.append(FingerPath(start, v, float(rng.uniform(0.005, 0.010)), 0, FRAMES + 3))
    return pair[0], pair[1]


def episode(seed: int, base: SceneConfig | None = None) -> Episode:
    """The episode of a seed (the same on every machine), its settings those of
    ``base`` (default: the built-in scene)."""
    rng = np.random.default_rng([seed, 2026])
    first = (float(rng.uniform(-0.04, 0.04)), float(rng.uniform(-0.03, 0.03)))
    objects = [_object(rng, "a", first)]
    if rng.random() < 0.5:
        angle = float(rng.uniform(0.0, 2.0 * math.pi))
        second = (first[0] + 0.09 * math.cos(angle), first[1] + 0.09 * math.sin(angle))
        candidate = _object(rng, "b", second)
        reach = sum(math.hypot(*o.size[:2]) if o.shape == "box" else 2 * o.size[0] for o in objects)
        reach += (
            math.hypot(*candidate.size[:2]) if candidate.shape == "box" else 2 * candidate.size[0]
        )
        inside = all(abs(c) < h - 0.06 for c, h in zip(second, (0.16, 0.12), strict=True))
        if 0.5 * reach + 0.01 < 0.09 and inside:
            objects.append(candidate)
    fingers = [_finger(rng, first) for _ in range(int(rng.integers(1, 6)))]
    if rng.random() < 1.0 / 3.0:
        fingers[-1:] = list(_crossing_pair(rng, first))
    noise = None
    if rng.random() < 0.5:
        noise = SensorNoise(
            blur_sigma=float(rng.uniform(0.0, 1.5)),
            salt_pepper=float(rng.uniform(0.0, 5e-5)),
            holes=int(rng.integers(0, 5)),
            hole_radius=float(rng.uniform(1.0, 4.0)),
            jitter=float(rng.uniform(0.0, 2.0)),
        )
    scene = (load_config(None) if base is None else base).replace(
        surface={"size": TABLE_SIZE, "resolution": TABLE_PIXELS},
        physics={"table_friction": float(rng.uniform(0.0, 2.0))},
        objects=[to_dict(o) for o in objects],
    )
    return Episode(seed, scene, tuple(fingers), noise)


@dataclass
class Outcome:
    """What one episode did: its violations (empty: clean), how close it came to the
    overlap allowance and how long it took.

    Attributes:
        deepest_mm: the deepest any particle overlapped an object in the episode,
            millimetres (negative: none overlapped one; -inf: no particle ever had
            an object to overlap; an empty cell in ``fuzz.csv``); the allowance is
            ``Tolerances.inside_object``.
    """

    seed: int
    description: str
    broken: list[str] = field(default_factory=list)
    first: str = ""
    seconds: float = 0.0
    deepest_mm: float = -math.inf


def play(seed: int, preset: str = "default", config: str | None = None) -> Outcome:
    """Play a seed's episode through the whole pipeline at a fidelity ``preset``
    (:data:`~graspenv.config.FIDELITY_PRESETS`) over the settings of the scene file
    ``config`` (default: the built-in scene), checking every frame."""
    tic = time.perf_counter()
    ep = episode(seed, None if config is None else load_config(config))
    hands = ep.hands()
    rng = np.random.default_rng(seed)
    with Simulation(at_fidelity(ep.scene, preset)) as sim:
        checker = InvariantChecker(sim, hand_speed(hands))
        empty = np.zeros(sim.surface.shape, np.uint8)
        for hand in hands + [None] * EMPTY_FRAMES:
            mask = empty if hand is None else render_mask(hand, sim.surface, ep.noise, rng)
            sim.step(mask)
            checker.check()
    return Outcome(
        seed,
        ep.describe(),
        sorted(checker.broken()),
        str(checker.violations[0]) if checker.violations else "",
        time.perf_counter() - tic,
        1000 * checker.worst.deepest_in_object,
    )


@dataclass
class FuzzReport:
    """Every episode's outcome, the run's wall time and the preset it ran at."""

    outcomes: list[Outcome]
    seconds: float
    preset: str = "default"
    config: str | None = None

    @property
    def failures(self) -> list[Outcome]:
        return [o for o in self.outcomes if o.broken]

    def text(self) -> str:
        counts: dict[str, int] = {}
        for outcome in self.failures:
            for name in outcome.broken:
                counts[name] = counts.get(name, 0) + 1
        lines = [
            f"{len(self.outcomes)} episodes at the {self.preset} preset"
            + (f" over {self.config}" if self.config else "")
            + f" in {self.seconds:.0f} s: "
            f"{len(self.failures)} broke an invariant"
            + (
                " (" + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + ")"
                if counts
                else ""
            )
        ]
        lines.append(self.overlap_tail())
        lines += [f"  seed {o.seed}: {o.first} [{o.description}]" for o in self.failures[:20]]
        if len(self.failures) > 20:
            lines.append(f"  ... and {len(self.failures) - 20} more in fuzz.csv")
        return "\n".join(lines)

    def overlap_tail(self) -> str:
        """How near the episodes came to the overlap allowance: the deepest particle
        overlap's median, 99th and 99.9th percentiles and maximum over the episodes
        in which a particle touched an object (with fewer than 1 000 of them the
        99.9th percentile is little more than the maximum)."""
        depths = np.array([o.deepest_mm for o in self.outcomes if o.deepest_mm > 0.0])
        if not len(depths):
            return "deepest particle overlap: no particle touched an object"
        allowed = 1000 * Tolerances().inside_object
        q50, q99, q999 = np.percentile(depths, [50, 99, 99.9])
        over_half = int(np.sum(depths > 0.5 * allowed))
        return (
            f"deepest particle overlap over {len(depths)} touching episodes: median "
            f"{q50:.3f} mm, 99th percentile {q99:.3f}, 99.9th {q999:.3f}, max "
            f"{depths.max():.3f} (allowed {allowed:g} mm; {over_half} past half of it)"
        )

    def write(self, path: Path) -> Path:
        return write_rows(
            [
                {
                    "seed": o.seed,
                    "preset": self.preset,
                    "broken": " ".join(o.broken),
                    "first_violation": o.first,
                    "episode": o.description,
                    "seconds": f"{o.seconds:.3f}",
                    "deepest_mm": f"{o.deepest_mm:.4f}" if math.isfinite(o.deepest_mm) else "",
                }
                for o in self.outcomes
            ],
            path,
        )


def run_fuzz(
    count: int,
    first_seed: int = 0,
    workers: int = 1,
    progress: Callable[[str], None] | None = None,
    preset: str = "default",
    config: str | None = None,
) -> FuzzReport:
    """Play episodes ``first_seed`` .. ``first_seed + count - 1`` (in ``workers``
    processes) at a fidelity ``preset`` over the settings of the scene file
    ``config`` (its objects and table are the episodes' own), reporting progress
    every 2 % of the run."""
    if count < 1 or workers < 1:
        raise ValueError(f"count and workers must be at least 1, got {count} and {workers}")
    resolve_fidelity(preset)  # a bad name fails here, not in a worker
    if config is not None:
        load_config(config)  # and so does a bad scene file
    tic = time.perf_counter()
    outcomes: list[Outcome] = []
    step = max(1, count // 50)

    def note(outcome: Outcome) -> None:
        outcomes.append(outcome)
        done = len(outcomes)
        if progress is not None and (done % step == 0 or done == count):
            bad = sum(1 for o in outcomes if o.broken)
            rate = done / (time.perf_counter() - tic)
            progress(f"[{done}/{count}] {bad} broke an invariant; {rate:.1f} episodes/s")

    seeds = range(first_seed, first_seed + count)
    run_jobs(
        functools.partial(play, preset=preset, config=config), seeds, workers, note, chunksize=8
    )
    return FuzzReport(outcomes, time.perf_counter() - tic, preset, config)
