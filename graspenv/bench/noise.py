"""Grasps through a real sensor's masks: ``graspenv bench --noise``.

A pair of fingertips squeezes, turns (90°) and slides (10 cm) a set of objects, the
masks seen through each noise level of :data:`LEVELS` (the two kinds of table of
:data:`graspenv.surface.TABLE_NOISE`, then the DI level two and four times over),
with each clean-up of :data:`CLEANUPS` in the contact pipeline: nothing, the
smallest-contact filter (``contacts.min_area``, on by default), and the filter with
a morphological closing (``contacts.close_px``), a fill of flickering dropouts from
the previous frame (``contacts.fill_px``) or both, both with the proxies'
smoothing of followed contours (``proxy.smoothing``), and both after a vote of each
pixel over the last three or five masks (``contacts.vote_frames``). Each run is
played with two noise seeds at a sub-pixel placement of its own.

Ground truth is the ideal rigid grasp: the object turns with the fingers and ends
where they carry it. A level passes with a clean-up when every run's turn is within
:data:`TURN_TARGET_DEG` and its slide within :data:`SLIDE_TARGET_PCT` of the travel,
and no object is dropped (a turn off by more than :data:`DROP_TURN_DEG` or a slide
by more than :data:`DROP_SLIDE_PCT`: the fingers went on without it).

Outputs: ``noise.csv`` (one row a run), ``noise.md`` (the table) and ``noise.png``
(the worst turn and slide error against noise level, one line a clean-up).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from graspenv.bench.grid import (
    SLIDE,
    TURN,
    Cell,
    base_scene,
    cell_from_row,
    grasp_run,
    placed,
    run_row,
)
from graspenv.bench.jobs import collect_jobs
from graspenv.bench.results import pipe_table, write_rows
from graspenv.plots import line_chart, write_png
from graspenv.surface.noise import TABLE_NOISE, SensorNoise

__all__ = [
    "CELLS",
    "CLEANUPS",
    "LEVELS",
    "NoiseRun",
    "run_noise",
    "summary",
    "write_outputs",
]

TURN_TARGET_DEG = 2.0
SLIDE_TARGET_PCT = 3.0
DROP_TURN_DEG = 30.0
DROP_SLIDE_PCT = 25.0
SEEDS = (0, 1)

#: Noise levels from none to four times the DI table's, weakest first.
LEVELS: dict[str, SensorNoise | None] = {
    "clean": None,
    "ftir": TABLE_NOISE["ftir"],
    "di": TABLE_NOISE["di"],
    "di x2": TABLE_NOISE["di"].scaled(2.0),
    "di x4": TABLE_NOISE["di"].scaled(4.0),
}


def _cleanup(
    min_area: float | str = "auto",
    close: int = 0,
    fill: int = 0,
    votes: int = 1,
    smoothing: float = 1.0,
) -> dict[str, dict[str, Any]]:
    """One clean-up as scene sections, every clean-up setting given, so that a scene
    file's own (``envs_configs/di_table.toml``) does not carry into the others."""
    return {
        "contacts": {
            "min_area": min_area,
            "close_px": close,
            "fill_px": fill,
            "vote_frames": votes,
        },
        "proxy": {"smoothing": smoothing},
    }


#: The clean-ups: the contact pipeline's (contacts-section overrides) and the
#: proxies' smoothing of followed contours (proxy section), as scene sections.
CLEANUPS: dict[str, dict[str, dict[str, Any]]] = {
    "none": _cleanup(min_area=0.0),
    "speck filter": _cleanup(),
    "filter + close 5 px": _cleanup(close=5),
    "filter + fill 2 px": _cleanup(fill=2),
    "filter + close 5 + fill 2": _cleanup(close=5, fill=2),
    "close 5 + fill 2 + smoothing 0.5": _cleanup(close=5, fill=2, smoothing=0.5),
    "vote 3 + close 5 + fill 2": _cleanup(close=5, fill=2, votes=3),
    "vote 5 + close 5 + fill 2": _cleanup(close=5, fill=2, votes=5),
}

#: The objects: the canonical box and the grid's hard corners of it (light, small,
#: tall, round), each gripped 3 mm deep by 8 mm fingertips.
CELLS: tuple[Cell, ...] = (
    Cell(),
    Cell(mass=0.02),
    Cell(footprint=0.03),
    Cell(height=0.06),
    Cell(shape="cylinder"),
)


@dataclass(frozen=True)
class NoiseRun:
    """One object's turn and slide at one noise level, clean-up and seed."""

    level: str
    cleanup: str
    cell: Cell
    seed: int
    turn_error_deg: float
    slide_error_pct: float

    @property
    def dropped(self) -> bool:
        return not (
            abs(self.turn_error_deg) <= DROP_TURN_DEG
            and abs(self.slide_error_pct) <= DROP_SLIDE_PCT
        )

    @property
    def ok(self) -> bool:
        return abs(self.turn_error_deg) <= TURN_TARGET_DEG and (
            abs(self.slide_error_pct) <= SLIDE_TARGET_PCT
        )

    def row(self) -> dict[str, object]:
        return {**run_row(self, "level", "cleanup"), "dropped": self.dropped}


#: One run: noise level, clean-up, object, seed, scene file (None: the built-in
#: default) and fidelity preset.
Job = tuple[str, str, Cell, int, str | None, str]


def _jobs(
    cells: Sequence[Cell],
    config: str | None,
    preset: str,
    seeds: Sequence[int],
    levels: Sequence[str],
) -> list[Job]:
    jobs: list[Job] = []
    for seed in seeds:
        for cell in placed(cells, seed):
            for level in levels:
                for cleanup in CLEANUPS:
                    jobs.append((level, cleanup, cell, seed, config, preset))
    return jobs


def measure(job: Job) -> NoiseRun:
    """Play one job's turn and slide (module docstring)."""
    level, cleanup, cell, seed, config, preset = job
    base = base_scene(config, preset).replace(**CLEANUPS[cleanup])
    noise = LEVELS[level]
    _, turned, _, _ = grasp_run(base, cell, "turn", noise, seed)
    final, _, _, _ = grasp_run(base, cell, "slide", noise, seed)
    ideal = (cell.position[0], cell.position[1] + SLIDE)
    slide = 100.0 * math.hypot(final[0] - ideal[0], final[1] - ideal[1]) / SLIDE
    return NoiseRun(level, cleanup, cell, seed, math.degrees(turned - TURN), slide)


def run_noise(
    cells: Sequence[Cell] = CELLS,
    workers: int = 1,
    progress: Callable[[str], None] | None = None,
    config: str | None = None,
    preset: str = "default",
    seeds: Sequence[int] = SEEDS,
    levels: Sequence[str] = tuple(LEVELS),
) -> list[NoiseRun]:
    """Every object at every level of ``levels`` (names of :data:`LEVELS`) with every
    clean-up and noise seed (each seed at a placement of its own), in ``workers``
    processes, on the scene file ``config`` (or the built-in default) at a fidelity
    ``preset``."""
    base_scene(config, preset)  # a bad file or preset fails here, not in a worker
    unknown = sorted(set(levels) - set(LEVELS))
    if unknown or not levels:
        raise ValueError(f"noise levels must be some of {list(LEVELS)}, got {list(levels)}")
    if not seeds or any(seed < 0 for seed in seeds):
        raise ValueError(f"noise seeds must be one or more whole numbers >= 0, got {list(seeds)}")
    jobs = _jobs(cells, config, preset, seeds, levels)
    return collect_jobs(measure, jobs, workers, progress, _describe)


def _describe(run: NoiseRun) -> str:
    return (
        f"{run.level}, {run.cleanup}: {run.cell.label()},"
        f" seed {run.seed}: turn {run.turn_error_deg:+.2f} deg,"
        f" slide {run.slide_error_pct:.2f} %{' DROPPED' if run.dropped else ''}"
    )


def _worst(runs: Sequence[NoiseRun], level: str, cleanup: str) -> tuple[float, float, int, int]:
    chosen = [r for r in runs if r.level == level and r.cleanup == cleanup]
    turn = max((abs(r.turn_error_deg) for r in chosen), default=math.nan)
    slide = max((abs(r.slide_error_pct) for r in chosen), default=math.nan)
    return turn, slide, sum(r.dropped for r in chosen), len(chosen)


def summary(runs: Sequence[NoiseRun]) -> str:
    """Markdown: for each level and clean-up, the worst turn and slide errors, the
    drops and whether it meets the targets."""
    header = (
        "noise",
        "clean-up",
        "worst turn",
        "worst slide",
        "dropped",
        f"within {TURN_TARGET_DEG:g}° and {SLIDE_TARGET_PCT:g} %",
    )
    rows = []
    for level in LEVELS:
        for cleanup in CLEANUPS:
            turn, slide, dropped, n = _worst(runs, level, cleanup)
            if n == 0:
                continue
            ok = sum(r.ok for r in runs if r.level == level and r.cleanup == cleanup)
            rows.append(
                (level, cleanup, f"{turn:.2f}°", f"{slide:.2f} %", f"{dropped}/{n}", f"{ok}/{n}")
            )
    return pipe_table(header, rows)


def write_csv(runs: Sequence[NoiseRun], path: Path) -> Path:
    return write_rows([r.row() for r in runs], path)


def read_csv(path: Path) -> list[NoiseRun]:
    """Runs written by :func:`write_csv`."""
    runs = []
    with path.open() as f:
        for row in csv.DictReader(f):
            runs.append(
                NoiseRun(
                    row["level"],
                    row["cleanup"],
                    cell_from_row(row),
                    int(row["seed"]),
                    float(row["turn_error_deg"]),
                    float(row["slide_error_pct"]),
                )
            )
    return runs


def chart(runs: Sequence[NoiseRun], path: Path) -> Path:
    """The worst turn and slide errors against noise level, one line a clean-up,
    the two panels side by side (a dropped object is drawn at the chart's top)."""
    levels = [name for name in LEVELS if any(r.level == name for r in runs)]
    x = list(range(len(levels)))
    panels = []
    for index, (title, target) in enumerate(
        ((f"worst turn error (deg), target {TURN_TARGET_DEG:g}", TURN_TARGET_DEG),
         (f"worst slide error (%), target {SLIDE_TARGET_PCT:g}", SLIDE_TARGET_PCT))
    ):  # fmt: skip
        top = 4.0 * target
        title += f" (drawn up to {top:g})"
        series = {}
        for cleanup in CLEANUPS:
            ys = [min(_worst(runs, level, cleanup)[index], top) for level in levels]
            series[cleanup] = (x, ys)
        panels.append(
            line_chart(
                series,
                None,
                title,
                "noise level",
                "",
                ylim=(0.0, top),
                size=(620, 400),
                categories=levels,
                guides={f"target {target:g}": target},
            )
        )
    return write_png(np.concatenate(panels, axis=1), path)


def write_outputs(runs: Sequence[NoiseRun], out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    md = out / "noise.md"
    md.write_text(summary(runs) + "\n")
    return [write_csv(runs, out / "noise.csv"), md, chart(runs, out / "noise.png")]
