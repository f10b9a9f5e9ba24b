"""Playing a scripted hand through the whole pipeline, timing each stage.

:func:`play` renders every frame of a :class:`~graspenv.surface.scripts.Script`,
steps a fresh :class:`~graspenv.simulation.Simulation` with the masks and returns
what it measured as a :class:`Played`: frames, per-stage seconds, particle counts,
the final object poses and the contour-point tracking error (for each particle
that continues from one frame to the next, its contour point against where the
finger's true rigid motion takes the previous point). The scenarios
(:mod:`graspenv.bench.scenarios`) and the grid (:mod:`graspenv.bench.grid`) are
built on it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from graspenv.config import SceneConfig
from graspenv.geometry import yaw_of
from graspenv.simulation import Simulation
from graspenv.surface.hand import Hand
from graspenv.surface.noise import SensorNoise
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import Script

__all__ = ["Played", "Points", "play"]


@dataclass
class Played:
    """What one scripted run measured."""

    frames: int = 0
    stage_seconds: dict[str, float] = field(default_factory=dict)
    particles: list[int] = field(default_factory=list)
    tracking_sq: list[float] = field(default_factory=list)
    final: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    errors: dict[str, float] = field(default_factory=dict)

    def add_timings(self, timings: dict[str, float]) -> None:
        for stage, seconds in timings.items():
            self.stage_seconds[stage] = self.stage_seconds.get(stage, 0.0) + seconds


def _nearest_shape(hand: Hand, points: NDArray[np.float64]) -> list[str]:
    names = [name for name, _shape, down in hand if down]
    if not names:
        return []
    distance = np.stack([np.abs(hand[n].signed_distance(points)) for n in names])
    return [names[i] for i in distance.argmin(axis=0)]


#: Particle id → its contour point, metres, world frame, (2,).
Points = dict[int, NDArray[np.float64]]


def _tracking_errors(hand: Hand, dt: float, before: Points, after: Points) -> list[float]:
    """Squared errors (m²) of continuing particles against the true finger motion."""
    common = sorted(set(before) & set(after))
    if not common:
        return []
    points = np.array([before[i] for i in common])
    now = np.array([after[i] for i in common])
    moved = points.copy()
    shapes = _nearest_shape(hand, points)
    for name in set(shapes):
        rows = [k for k, s in enumerate(shapes) if s == name]
        moved[rows] += hand.displacement(name, points[rows], dt)
    return list(np.sum((now - moved) ** 2, axis=1))


def play(
    scene: SceneConfig,
    script: Script,
    objects: Sequence[str],
    tracked_phases: Iterable[str] = (),
    noise: SensorNoise | None = None,
    each_frame: Callable[[Simulation, int, Played], bool] | None = None,
    extra_frames: int = 0,
    replays: int = 1,
    noise_seed: int = 0,
) -> Played:
    """Play a script through a fresh simulation, timing each stage.

    With ``replays`` R > 1 the same masks are played R - 1 more times through the
    rebuilt simulation (bit-identical runs) and each stage's time in each frame is
    the smallest of the R: on a shared machine a neighbour's burst slows single
    frames, and the minimum leaves those out. A run with ``each_frame`` (which may
    act on the simulation and keep state of its own) is timed once.

    Args:
        scene: the scene (its objects must include ``objects``).
        script: the scripted hand.
        objects: the objects whose final poses are kept.
        tracked_phases: phases in which the tracking error is measured (the finger
            shapes must move rigidly there: no touch-downs or presses).
        noise: sensor noise applied to every mask (seeded per run by
            ``noise_seed``).
        each_frame: called after every frame; returning True ends the run.
        extra_frames: empty frames after the script.
        replays: timing runs (see above), >= 1.
    """
    if replays < 1:
        raise ValueError(f"replays must be >= 1, got {replays}")
    result = Played()
    rng = np.random.default_rng(noise_seed)
    tracked = {
        i for name, frames in script.phase_ranges() if name in tracked_phases for i in frames
    }
    with Simulation(scene) as sim:
        dt = sim.surface.dt
        hands: list[Hand | None] = [hand for _, hand in script.frames(sim.surface)]
        empty = np.zeros(sim.surface.shape, np.uint8)
        previous: Points = {}
        masks: list[NDArray[np.uint8]] = []
        timings: list[dict[str, float]] = []
        for index, hand in enumerate(hands + [None] * extra_frames):
            mask = empty if hand is None else render_mask(hand, sim.surface)
            if noise is not None and hand is not None:
                mask = noise.apply(mask, rng)
            masks.append(mask)
            report = sim.step(mask)
            result.frames += 1
            timings.append(report.timings)
            result.particles.append(report.n_particles)
            # Each continuing particle's contour point, in tracked frames only.
            now: Points = {}
            if index in tracked and report.command.particles.size:
                command = report.command
                # A particle put down this frame may have served another point before.
                born = command.born if command.born.size else np.zeros(len(command.targets), bool)
                now = {
                    int(p): command.targets[k]
                    for k, p in enumerate(command.particles[:, 0])
                    if not born[k]
                }
            if index - 1 in tracked and index in tracked:
                before_hand = hands[index - 1]
                assert before_hand is not None
                result.tracking_sq += _tracking_errors(before_hand, dt, previous, now)
            previous = now
            if each_frame is not None and each_frame(sim, index, result):
                break
        for name in objects:
            position, q = sim.object_pose(name)
            result.final[name] = np.array([*position, yaw_of(q)])
        for _ in range(replays - 1 if each_frame is None else 0):
            sim.reset(scene)
            for index, mask in enumerate(masks):
                again = sim.step(mask).timings
                timings[index] = {k: min(v, again[k]) for k, v in timings[index].items()}
    for frame in timings:
        result.add_timings(frame)
    return result
