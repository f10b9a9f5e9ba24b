"""``graspenv bench --speed``: how fast the whole pipeline runs, in one run.

Headline figures are wall clocks of whole runs, what a user sees:

- **Scenes.** The canonical two-finger turn (:func:`~graspenv.bench.scenarios.turn_scene`)
  at the default and ``fast`` presets and with envs_configs/coarse.toml (the
  ``fast`` preset until 2026-12-06), and the ten-finger two-hand carry at the
  default: the masks are rendered first, then a new :class:`Simulation` plays them
  all; the figure is simulated time over the wall time of that whole loop (the median
  of ``runs`` runs, with the range). Bullet's share is the time inside its
  ``stepSimulation`` over that wall time. A per-stage breakdown (the minimum of each
  frame's stage times over the runs) is given beside it, and says so.
- **Environments.** Every environment's steps per second with its scripted agent
  (the ``graspenv.strategies`` entry points; the repository's agents, installed as
  ``graspenv_agents``, register them) and with seeded random actions, beside panda-gym's
  ``PandaPickAndPlace-v3`` (random actions, state observations; the PyBullet peer a
  user would pick) measured in the same process before and after, so that each ratio
  comes from one run on one machine. Resets are timed on their own.
- **Contacts.** Frame cost against the number of contacts: 1, 10, 100 and 1 000
  fingertips, and as many noise speckles (3 × 3 pixels, drawn anew each frame).
- **Compilation.** The first call of every compiled kernel in a fresh process with an
  empty numba cache, then again in another fresh process with that cache: the second
  pays only the load.

Nothing here is a test: speeds on a shared machine vary by a quarter from hour to
hour, so only ratios from one run mean much (docs/design.md, "How we measure").
"""

from __future__ import annotations

import csv
import importlib.util
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.bench.frontier import COARSE
from graspenv.bench.scenarios import turn_scene, two_hands_scene
from graspenv.config import FIDELITY_PRESETS, SceneConfig, load_config
from graspenv.simulation import STAGES, Simulation
from graspenv.surface.render import render_mask
from graspenv.surface.scripts import Script

__all__ = ["SpeedReport", "run_speed"]

#: The peer environment measured side by side.
PEER_ID = "PandaPickAndPlace-v3"
#: Contact counts of the scaling benchmark.
CONTACT_COUNTS = (1, 10, 100, 1000)
SPECKLE_PIXELS = 3
SCALING_FRAMES = 20

Progress = Callable[[str], None]


@dataclass
class SceneSpeed:
    """Whole runs of one scene."""

    name: str
    frames: int
    fps: float
    walls: list[float]
    bullet: list[float]
    stage_minima: dict[str, float]

    @property
    def realtime(self) -> float:
        """Median simulated seconds per wall second."""
        return self.frames / self.fps / float(np.median(self.walls))

    @property
    def realtime_range(self) -> tuple[float, float]:
        return self.frames / self.fps / max(self.walls), self.frames / self.fps / min(self.walls)

    @property
    def bullet_share(self) -> float:
        """Bullet's step over the whole run's wall time (median run)."""
        shares = [b / w for b, w in zip(self.bullet, self.walls, strict=True)]
        return float(np.median(shares))


@dataclass
class EnvSpeed:
    """Steps per second of one environment."""

    env_id: str
    strategy: str
    scripted: float
    random: float


@dataclass
class ScalingPoint:
    """One mask kind and count: the median frame's cost and the means of the rest."""

    kind: str
    requested: int
    contacts: float
    points: float
    particles: float
    frame_ms: float


@dataclass
class SpeedReport:
    scenes: list[SceneSpeed] = field(default_factory=list)
    envs: list[EnvSpeed] = field(default_factory=list)
    peer: float = math.nan
    reset_ms: dict[str, float] = field(default_factory=dict)
    scaling: list[ScalingPoint] = field(default_factory=list)
    compile_s: dict[str, float] = field(default_factory=dict)
    machine: str = ""

    # -- the targets -------------------------------------------------------------------

    def scene(self, name: str) -> SceneSpeed | None:
        return next((s for s in self.scenes if s.name == name), None)

    def targets(self) -> list[tuple[str, str, str, bool | None]]:
        """(figure, measured, target, met) of the issue's table (README)."""
        rows: list[tuple[str, str, str, bool | None]] = []

        def scene_row(label: str, name: str, target: float) -> None:
            s = self.scene(name)
            if s is not None:
                lo, hi = s.realtime_range
                rows.append(
                    (
                        label,
                        f"{s.realtime:.1f}× real time ({lo:.1f}–{hi:.1f})",
                        f"≥ {target:g}×",
                        s.realtime >= target,
                    )
                )

        scene_row("canonical turn, default fidelity", "turn, default", 12)
        # 20× was issue 12's target for `fast` when it was the coarse setting. The
        # preset now meets issue 13's accuracy target instead (within twice the
        # default's error) and is not at 20×; the coarse file is (README, "Speed
        # against error"). Both rows stay, so the table says which is met.
        scene_row("canonical turn, `fast`", "turn, fast", 20)
        scene_row("canonical turn, envs_configs/coarse.toml", "turn, coarse", 20)
        scene_row("ten-finger scene, default", "two hands, default", 5)
        turn = self.scene("turn, default")
        if turn is not None:
            rows.append(
                (
                    "Bullet's share of the canonical frame",
                    f"{100 * turn.bullet_share:.0f} %",
                    "≥ 50 %",
                    turn.bullet_share >= 0.5,
                )
            )
        for kind in ("fingertips", "speckles"):
            by_count = {p.requested: p for p in self.scaling if p.kind == kind}
            if 10 in by_count and 100 in by_count:
                factor = by_count[100].frame_ms / by_count[10].frame_ms
                rows.append(
                    (
                        f"frame cost for 10× the contacts ({kind}, 10 → 100)",
                        f"×{factor:.1f}",
                        "≤ ×15",
                        factor <= 15,
                    )
                )
        speckles = {p.requested: p for p in self.scaling if p.kind == "speckles"}
        if 100 in speckles and 1000 in speckles:
            # 300 speckles between the measured 100 and 1 000, log-log.
            a, b = speckles[100], speckles[1000]
            slope = math.log(b.frame_ms / a.frame_ms) / math.log(10)
            at_300 = a.frame_ms * 3**slope
            rows.append(
                (
                    "300 speckles (interpolated)",
                    f"{at_300:.1f} ms a frame",
                    "< 16.7 ms",
                    at_300 < 1000 / 60,
                )
            )
        for label, ratios, target in (
            ("scripted agents", [e.scripted / self.peer for e in self.envs], 1.0),
            ("random actions", [e.random / self.peer for e in self.envs], 1.5),
        ):
            ratios = [r for r in ratios if math.isfinite(r)]
            if ratios:
                rows.append(
                    (
                        f"env steps/s vs panda-gym, {label}",
                        f"{min(ratios):.2f}–{max(ratios):.2f}× (median {np.median(ratios):.2f}×)",
                        f"≥ {target:g}×",
                        min(ratios) >= target,
                    )
                )
        if "simulation, same scene" in self.reset_ms:
            worst = max(self.reset_ms.values())
            rows.append(
                (
                    "reset",
                    ", ".join(f"{k}: {v:.1f} ms" for k, v in self.reset_ms.items()),
                    "≤ 5 ms",
                    worst <= 5.0,
                )
            )
        return rows

    # -- output ------------------------------------------------------------------------

    def markdown(self) -> str:
        lines = [f"Measured on {self.machine}.", ""]
        lines += ["| figure | measured | target | met |", "|---|---|---|---|"]
        for figure, value, target, met in self.targets():
            mark = "—" if met is None else ("yes" if met else "**no**")
            lines.append(f"| {figure} | {value} | {target} | {mark} |")
        lines += ["", "Whole runs (median of the runs; range in brackets):", ""]
        lines += [
            "| scene | frames | × real time | Bullet's share | per-stage minima, ms a frame |",
            "|---|---|---|---|---|",
        ]
        for s in self.scenes:
            lo, hi = s.realtime_range
            stages = ", ".join(f"{k} {v * 1e3:.3f}" for k, v in s.stage_minima.items())
            lines.append(
                f"| {s.name} | {s.frames} | {s.realtime:.1f} ({lo:.1f}–{hi:.1f}) | "
                f"{100 * s.bullet_share:.0f} % | {stages} |"
            )
        if self.envs:
            lines += ["", f"Environment steps per second ({PEER_ID}: {self.peer:.0f}):", ""]
            lines += [
                "| environment | scripted agent | steps/s | vs panda-gym | random steps/s "
                "| vs panda-gym |",
                "|---|---|---|---|---|---|",
            ]
            for e in self.envs:
                scripted = f"{e.scripted:.0f} | {e.scripted / self.peer:.2f}×"
                if not math.isfinite(e.scripted):
                    scripted = "— | —"
                lines.append(
                    f"| `{e.env_id}` | {e.strategy or '—'} | {scripted} | {e.random:.0f} | "
                    f"{e.random / self.peer:.2f}× |"
                )
        if self.scaling:
            lines += ["", "Frame cost against contacts (median frame):", ""]
            lines += [
                "| drawn | kind | contacts seen | contour points | particles | ms a frame |",
                "|---|---|---|---|---|---|",
            ]
            for p in self.scaling:
                lines.append(
                    f"| {p.requested} | {p.kind} | {p.contacts:.0f} | {p.points:.0f} | "
                    f"{p.particles:.0f} | {p.frame_ms:.2f} |"
                )
        if self.compile_s:
            lines += ["", "Compiled kernels, one fresh process each:", ""]
            lines += [f"- {k}: {v:.1f} s" for k, v in self.compile_s.items()]
        return "\n".join(lines)

    def write(self, out: Path) -> list[Path]:
        out.mkdir(parents=True, exist_ok=True)
        table = out / "speed.md"
        table.write_text(self.markdown() + "\n")
        rows = out / "speed.csv"
        with rows.open("w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(["section", "name", "figure", "value"])
            for s in self.scenes:
                writer.writerow(["scene", s.name, "realtime", f"{s.realtime:.3f}"])
                writer.writerow(["scene", s.name, "bullet_share", f"{s.bullet_share:.3f}"])
                for k, v in s.stage_minima.items():
                    writer.writerow(["scene", s.name, f"min_{k}_ms", f"{v * 1e3:.4f}"])
            writer.writerow(["env", PEER_ID, "steps_per_s", f"{self.peer:.1f}"])
            for e in self.envs:
                writer.writerow(["env", e.env_id, "scripted_steps_per_s", f"{e.scripted:.1f}"])
                writer.writerow(["env", e.env_id, "random_steps_per_s", f"{e.random:.1f}"])
            for k, v in self.reset_ms.items():
                writer.writerow(["reset", k, "ms", f"{v:.3f}"])
            for p in self.scaling:
                for figure, value in (
                    ("contacts", p.contacts),
                    ("points", p.points),
                    ("particles", p.particles),
                    ("ms", p.frame_ms),
                ):
                    writer.writerow(["scaling", p.kind, f"{p.requested}_{figure}", f"{value:.4f}"])
            for k, v in self.compile_s.items():
                writer.writerow(["compile", k, "s", f"{v:.2f}"])
        written = [table, rows]
        if self.scaling:
            written.append(scaling_plot(self.scaling, out / "scaling.png"))
        return written


# -- scenes --------------------------------------------------------------------------------


def _masks(scene: SceneConfig, script: Script) -> list[NDArray[np.uint8]]:
    with Simulation(scene) as sim:
        return [render_mask(hand, sim.surface) for _, hand in script.frames(sim.surface)]


def scene_speed(
    name: str, scene: SceneConfig, masks: Sequence[NDArray[np.uint8]], runs: int
) -> SceneSpeed:
    """Whole runs of a new simulation over pre-rendered masks (module docstring)."""
    walls, bullet = [], []
    minima: list[dict[str, float]] | None = None
    with Simulation(scene) as sim:  # untimed: the process's first frames load kernels
        for mask in masks[:10]:
            sim.step(mask)
    for _ in range(runs):
        with Simulation(scene) as sim:
            clock = time.perf_counter
            start = clock()
            timings = [sim.step(mask).timings for mask in masks]
            walls.append(clock() - start)
        bullet.append(sum(t["physics"] for t in timings))
        minima = (
            timings
            if minima is None
            else [
                {k: min(a[k], b[k]) for k in STAGES} for a, b in zip(minima, timings, strict=True)
            ]
        )
    assert minima is not None
    stage = {k: sum(t[k] for t in minima) / len(masks) for k in STAGES}
    return SceneSpeed(name, len(masks), scene.surface.fps, walls, bullet, stage)


def scene_speeds(runs: int, progress: Progress) -> list[SceneSpeed]:
    """The canonical turn at the default and ``fast`` presets and the coarse setting,
    and the ten-finger scene at the default."""
    base = load_config(None)
    canonical, script = turn_scene(base)
    hands, hands_script, _, _ = two_hands_scene(base)
    turn_masks = _masks(canonical, script)  # the fast preset sees the same masks
    fast = turn_scene(base.replace(**FIDELITY_PRESETS["fast"]))[0]
    coarse = turn_scene(base.replace(**COARSE))[0]
    speeds = []
    for name, scene, masks in (
        ("turn, default", canonical, turn_masks),
        ("turn, fast", fast, turn_masks),
        ("turn, coarse", coarse, turn_masks),
        ("two hands, default", hands, _masks(hands, hands_script)),
    ):
        speeds.append(scene_speed(name, scene, masks, runs))
        progress(f"scene: {name} → {speeds[-1].realtime:.1f}× real time")
    return speeds


# -- environments ----------------------------------------------------------------------------


def _strategies() -> dict[str, tuple[str, Any]]:
    """env id → (strategy name, agent class) of the first registered scripted strategy
    with the environment's own arguments (``graspenv.strategies`` entry points)."""
    from importlib.metadata import entry_points

    found: dict[str, tuple[str, Any]] = {}
    for ep in sorted(entry_points(group="graspenv.strategies"), key=lambda e: e.name):
        try:
            table = ep.load()
        except ImportError:
            continue
        for name, strategy in table.items():
            if not strategy.env_kwargs and strategy.env_id not in found:
                found[strategy.env_id] = (name, strategy.agent)
    return found


def env_steps_per_second(
    env_id: str, steps: int, agent_cls: Any | None = None, seed: int = 0
) -> float:
    """Steps per second over ``steps`` steps (resets included, as a user sees them)
    after a warm-up episode; seeded random actions without an agent."""
    import gymnasium as gym

    env = gym.make(env_id)
    try:
        agent = agent_cls(env) if agent_cls is not None else None
        env.action_space.seed(seed)

        def act(obs: Any) -> Any:
            if agent is None:
                return env.action_space.sample()
            return agent.predict(obs, deterministic=True)[0]

        def play(n: int, episode_seed: int) -> float:
            obs, _ = env.reset(seed=episode_seed)
            if agent is not None and hasattr(agent, "reset"):
                agent.reset()
            start = time.perf_counter()
            for _ in range(n):
                obs, _, terminated, truncated, _ = env.step(act(obs))
                if terminated or truncated:
                    obs, _ = env.reset()
                    if agent is not None and hasattr(agent, "reset"):
                        agent.reset()
            return time.perf_counter() - start

        play(min(steps, 50), seed + 1)  # warm-up: caches, kernels, the pool
        return steps / play(steps, seed)
    finally:
        env.close()


def peer_available() -> bool:
    return importlib.util.find_spec("panda_gym") is not None


def peer_steps_per_second(steps: int) -> float:
    import panda_gym  # noqa: F401  (registers its environments)

    return env_steps_per_second(PEER_ID, steps)


def reset_times(samples: int = 30) -> dict[str, float]:
    """Median reset time, ms: a simulation put back to the same scene, and an
    environment drawing a new object every episode."""
    import gymnasium as gym

    import graspenv  # noqa: F401  (registers the environments)

    scene, _ = turn_scene(load_config(None))
    times = []
    with Simulation(scene) as sim:
        for _ in range(samples + 3):
            start = time.perf_counter()
            sim.reset(scene)
            times.append(time.perf_counter() - start)
    result = {"simulation, same scene": 1e3 * float(np.median(times[3:]))}
    env = gym.make("graspenv/TurnInPlace-v0")
    times = []
    for seed in range(samples + 3):
        start = time.perf_counter()
        env.reset(seed=seed)
        times.append(time.perf_counter() - start)
    env.close()
    result["environment, new object"] = 1e3 * float(np.median(times[3:]))
    return result


# -- contacts -------------------------------------------------------------------------------


def fingertip_masks(count: int, frames: int, shape: tuple[int, int]) -> list[NDArray[np.uint8]]:
    """``count`` round fingertips on a grid over the table, sliding 0.5 px a frame."""
    rows, columns = shape
    side = math.ceil(math.sqrt(count))
    step = min((columns - 40) / side, (rows - 40) / side)
    radius = max(2, min(9, int(step / 2) - 2))
    centres = [(20 + step * (i % side + 0.5), 20 + step * (i // side + 0.5)) for i in range(count)]
    masks = []
    for f in range(frames):
        mask = np.zeros(shape, np.uint8)
        for x, y in centres:
            cv2.circle(mask, (round(x + 0.5 * f), round(y)), radius, 255, -1)
        masks.append(mask)
    return masks


def speckle_masks(
    count: int, frames: int, shape: tuple[int, int], seed: int = 0
) -> list[NDArray[np.uint8]]:
    """``count`` square speckles of :data:`SPECKLE_PIXELS`, anywhere, anew each frame."""
    rng = np.random.default_rng(seed)
    rows, columns = shape
    size = SPECKLE_PIXELS
    masks = []
    for _ in range(frames):
        mask = np.zeros(shape, np.uint8)
        for r, c in zip(
            rng.integers(0, rows - size, count), rng.integers(0, columns - size, count), strict=True
        ):
            mask[r : r + size, c : c + size] = 255
        masks.append(mask)
    return masks


def scaling(
    frames: int = SCALING_FRAMES,
    progress: Progress | None = None,
    counts: Sequence[int] = CONTACT_COUNTS,
) -> list[ScalingPoint]:
    """Frame cost against contacts on the default scene (median frame after three)."""
    scene = load_config(None)
    shape = (scene.surface.resolution[1], scene.surface.resolution[0])
    points = []
    for kind, make in (("fingertips", fingertip_masks), ("speckles", speckle_masks)):
        for count in counts:
            masks = make(count, frames + 3, shape)
            costs, contacts, contour, particles = [], [], [], []
            with Simulation(scene) as sim:
                for i, mask in enumerate(masks):
                    start = time.perf_counter()
                    report = sim.step(mask)
                    if i >= 3:
                        costs.append(time.perf_counter() - start)
                        contacts.append(report.n_contacts)
                        contour.append(len(report.contacts.contours))
                        particles.append(report.n_particles)
            points.append(
                ScalingPoint(
                    kind,
                    count,
                    float(np.mean(contacts)),
                    float(np.mean(contour)),
                    float(np.mean(particles)),
                    1e3 * float(np.median(costs)),
                )
            )
            if progress is not None:
                progress(f"contacts: {count} {kind} → {points[-1].frame_ms:.2f} ms a frame")
    return points


def scaling_plot(points: Sequence[ScalingPoint], path: Path) -> Path:
    """Frame cost against contacts, log-log, one line per kind."""
    from graspenv.plots import line_chart

    series = {}
    for kind in dict.fromkeys(p.kind for p in points):
        rows = [p for p in points if p.kind == kind]
        series[kind] = (
            [math.log10(p.requested) for p in rows],
            [math.log10(p.frame_ms) for p in rows],
        )
    line_chart(
        series,
        path,
        "Frame cost against contacts (log-log; a slope of 1 is linear)",
        "log10 contacts drawn in the mask",
        "log10 ms a frame",
    )
    return path


# -- compilation ----------------------------------------------------------------------------

_FIRST_FRAME = """
import time, numpy as np
start = time.perf_counter()
import gymnasium as gym
import graspenv
from graspenv.bench.speed import fingertip_masks
env = gym.make("graspenv/TurnInPlace-v0")
obs, _ = env.reset(seed=0)
for _ in range(3):
    env.step(env.action_space.sample())
with graspenv.make_simulation() as sim:
    for mask in fingertip_masks(3, 3, sim.surface.shape):
        sim.step(mask)
print(time.perf_counter() - start)
"""


def compile_times() -> dict[str, float]:
    """Seconds from import to a few environment steps and frames: in a fresh process
    with an empty numba cache (everything compiles), then in another with that cache
    (the code is loaded)."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}

        def run() -> float:
            done = subprocess.run(
                [sys.executable, "-c", _FIRST_FRAME],
                env=env,
                capture_output=True,
                text=True,
                check=True,
            )
            return float(done.stdout.strip().splitlines()[-1])

        first = run()
        cached = run()
    return {"first run, empty cache (compiles)": first, "next process, cached": cached}


# -- the whole report -------------------------------------------------------------------------


def run_speed(
    progress: Progress | None = None,
    runs: int = 3,
    env_steps: int = 600,
    envs: Sequence[str] | None = None,
    with_scaling: bool = True,
    with_compile: bool = True,
    scenes: bool = True,
) -> SpeedReport:
    """Every figure of the module docstring, in one run.

    Args:
        progress: called with a line per finished part.
        runs: whole runs of each scene.
        env_steps: steps per environment measurement.
        envs: environment ids (default: all).
        with_scaling: run the contact scaling.
        with_compile: time the compilation in fresh processes.
        scenes: time the scenes.
    """
    import graspenv

    say = progress or (lambda _line: None)
    report = SpeedReport(machine=_machine())
    if scenes:
        report.scenes = scene_speeds(runs, say)
    ids = list(envs or graspenv.ENV_IDS)
    if ids:
        strategies = _strategies()
        peer = [peer_steps_per_second(env_steps)] if peer_available() else []
        for env_id in ids:
            name, agent = strategies.get(env_id, ("", None))
            scripted = env_steps_per_second(env_id, env_steps, agent) if agent else math.nan
            random = env_steps_per_second(env_id, env_steps)
            report.envs.append(EnvSpeed(env_id, name, scripted, random))
            say(f"env: {env_id} → scripted {scripted:.0f}, random {random:.0f} steps/s")
        if peer:
            peer.append(peer_steps_per_second(env_steps))
            report.peer = float(np.mean(peer))
            before, after = peer
            say(f"peer: {PEER_ID} → {report.peer:.0f} steps/s ({before:.0f}, then {after:.0f})")
        else:
            say(f"peer: panda-gym is not installed ({PEER_ID} not measured)")
        report.reset_ms = reset_times()
        say("resets: " + ", ".join(f"{k} {v:.1f} ms" for k, v in report.reset_ms.items()))
    if with_scaling:
        report.scaling = scaling(progress=say)
    if with_compile:
        report.compile_s = compile_times()
        say("compile: " + ", ".join(f"{k} {v:.1f} s" for k, v in report.compile_s.items()))
    return report


def _machine() -> str:
    import platform

    return (
        f"{platform.node() or 'this machine'}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()}, {time.strftime('%Y-%m-%d %H:%M')}"
    )
