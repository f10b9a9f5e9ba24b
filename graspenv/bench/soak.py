"""``graspenv bench --soak N``: a long run that must stay physical with flat memory.

The canonical grasp over and over in one simulation (never reset): two fingertips
come down either side of the box, squeeze, turn it 90° one way, 90° back, and
lift, so every cycle touches down, tracks, grows and releases particles through the
pool. After every frame the invariants of :mod:`graspenv.bench.invariants` are
checked; every :data:`SAMPLE` frames the process's resident memory is recorded.
Memory counts as flat when the last sample is within :data:`RSS_SLACK_MB` of the
sample taken after the first tenth of the run (allocators and caches settle first).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from graspenv.bench.interactions import BOX, pinch, with_objects
from graspenv.bench.invariants import InvariantChecker, hand_speed
from graspenv.bench.results import write_rows
from graspenv.bench.scenarios import DEPTH
from graspenv.config import SceneConfig, load_config
from graspenv.simulation import Simulation
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import GroupMotion, Phase

__all__ = ["SoakResult", "soak"]

SAMPLE = 1000
RSS_SLACK_MB = 5.0
LOWEST_IS_WORST = {"lowest_particle_mm", "height_margin_mm"}


def rss_mb() -> float:
    """Resident memory of this process, MB (Linux ``/proc``)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * 4096 / 2**20


@dataclass(frozen=True)
class SoakResult:
    frames: int
    seconds: float
    rss: list[tuple[int, float]]
    violations: int
    worst: dict[str, float]

    @property
    def growth_mb(self) -> float:
        settled = self.rss[max(len(self.rss) // 10, 1) - 1][1] if self.rss else 0.0
        return self.rss[-1][1] - settled if self.rss else 0.0

    @property
    def flat(self) -> bool:
        return self.growth_mb <= RSS_SLACK_MB

    def text(self) -> str:
        worst = ", ".join(f"{k} {v:.3g}" for k, v in self.worst.items())
        return (
            f"soak: {self.frames} frames in {self.seconds:.0f} s "
            f"({self.frames / self.seconds:.0f} frames/s); memory "
            f"{self.rss[0][1]:.0f} → {self.rss[-1][1]:.0f} MB (growth after settling "
            f"{self.growth_mb:+.1f} MB: {'flat' if self.flat else 'NOT flat'}); "
            f"invariant violations {self.violations}; worst: {worst}"
        )

    def write(self, path: Path) -> Path:
        return write_rows([{"frame": f, "rss_mb": mb} for f, mb in self.rss], path)


def soak(
    frames: int,
    config: str | SceneConfig | None = None,
    progress: Callable[[str], None] | None = None,
) -> SoakResult:
    """Run the grasp cycle for ``frames`` camera frames (see the module docstring)."""
    if frames < 1:
        raise ValueError(f"soak needs at least one frame, got {frames}")
    scene = with_objects(load_config(config), BOX)
    cycle = pinch(BOX, DEPTH, turn=math.pi / 2, turn_frames=60, slide_frames=0, hold_frames=5)
    back = Phase(60, group=GroupMotion(("thumb", "index"), rotation=-math.pi / 2), name="back")
    phases = list(cycle.phases)
    cycle = type(cycle)(cycle.hand, [*phases[:-1], back, phases[-1]])
    rss: list[tuple[int, float]] = []
    violations = 0
    worst: dict[str, float] = {}
    done = 0
    start = time.perf_counter()
    with Simulation(scene) as sim:
        hands = [hand for _, hand in cycle.frames(sim.surface)]
        masks = [render_mask(hand, sim.surface) for hand in hands]
        speed = hand_speed(hands)
        while done < frames:
            checker = InvariantChecker(sim, speed)
            for mask in masks[: frames - done]:
                sim.step(mask)
                checker.check()
                done += 1
                if done % SAMPLE == 0 or done == frames:
                    rss.append((done, rss_mb()))
                    if progress is not None and done % (10 * SAMPLE) == 0:
                        progress(f"[{done}/{frames}] frames, {rss[-1][1]:.0f} MB")
            violations += len(checker.violations)
            for key, value in checker.worst.as_dict().items():
                if np.isfinite(value):
                    pick = min if key in LOWEST_IS_WORST else max
                    worst[key] = pick(worst.get(key, value), value)
    return SoakResult(done, time.perf_counter() - start, rss, violations, worst)
