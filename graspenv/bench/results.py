"""The bench's results: one :class:`Result` per setting and scenario, and its outputs.

:func:`write_outputs` writes ``bench.csv`` (:func:`write_csv`; :func:`read_csv`
reads it back to draw the table and plot again), ``bench.md``
(:func:`markdown_table`) and ``pareto.png`` (:func:`pareto_png`).
:func:`write_rows` writes any list of rows as CSV and :func:`pipe_table` any table
as Markdown (the other benches use them too).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "HEADLINE",
    "PRESET_LABELS",
    "Result",
    "markdown_table",
    "pareto_png",
    "pipe_table",
    "read_csv",
    "write_csv",
    "write_outputs",
    "write_rows",
]


@dataclass(frozen=True)
class Result:
    """One scenario at one setting: errors, speed and stage shares."""

    setting: str
    scenario: str
    frames: int
    fps: float
    realtime: float
    bullet_share: float
    stage_fps: dict[str, float]
    mean_particles: float
    tracking_rms_mm: float
    tracking_rms_px: float
    reference_drift_mm: float
    errors: dict[str, float]
    placements: int = 1
    #: The Ray node that played the row (``graspenv bench --ray``), else "".
    node: str = ""

    def row(self) -> dict[str, Any]:
        row: dict[str, Any] = {
            "setting": self.setting,
            "scenario": self.scenario,
            "frames": self.frames,
            "placements": self.placements,
            "fps": round(self.fps, 1),
            "realtime": round(self.realtime, 2),
            "bullet_share": round(self.bullet_share, 3),
            "mean_particles": round(self.mean_particles, 1),
            "tracking_rms_mm": round(self.tracking_rms_mm, 4),
            "tracking_rms_px": round(self.tracking_rms_px, 3),
            "reference_drift_mm": round(self.reference_drift_mm, 3),
        }
        row.update({f"fps_{k}": round(v, 1) for k, v in self.stage_fps.items()})
        row.update({k: round(v, 4) for k, v in self.errors.items()})
        if self.node:
            row["node"] = self.node
        return row


def write_rows(rows: Sequence[Mapping[str, object]], path: Path) -> Path:
    """Rows as a CSV file, one column for each key any row has (in first-seen order)."""
    fields = list(dict.fromkeys(k for row in rows for k in row))
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    return path


def pipe_table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A Markdown pipe table: the header, its rule, then one line per row (each cell
    already formatted, or formatted by ``str``)."""
    lines = [_pipe_row(header), "|" + "---|" * len(header)]
    lines += [_pipe_row(row) for row in rows]
    return "\n".join(lines)


def _pipe_row(cells: Sequence[object]) -> str:
    return "| " + " | ".join(str(cell) for cell in cells) + " |"


def write_csv(results: Sequence[Result], path: Path) -> Path:
    return write_rows([r.row() for r in results], path)


_ROW_FIELDS = (
    "setting",
    "scenario",
    "frames",
    "placements",
    "fps",
    "realtime",
    "bullet_share",
    "mean_particles",
    "tracking_rms_mm",
    "tracking_rms_px",
    "reference_drift_mm",
)


def read_csv(path: Path) -> list[Result]:
    """The results of an earlier run from its ``bench.csv`` (values as rounded there),
    to draw its table and plot again without running it again.

    Raises:
        ValueError: the file is not a bench CSV (a column is missing).
    """
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    missing = [k for k in _ROW_FIELDS if rows and k not in rows[0]]
    if not rows or missing:
        raise ValueError(f"{path} is not a bench.csv: no rows or missing columns {missing}")

    def number(text: str) -> float:
        return float(text) if text != "" else math.nan

    results = []
    for row in rows:
        stages = {k[4:]: number(v) for k, v in row.items() if k.startswith("fps_")}
        errors = {
            k: number(v)
            for k, v in row.items()
            if k not in _ROW_FIELDS and k != "node" and not k.startswith("fps_") and v != ""
        }
        results.append(
            Result(
                setting=row["setting"],
                scenario=row["scenario"],
                frames=int(row["frames"]),
                fps=number(row["fps"]),
                realtime=number(row["realtime"]),
                bullet_share=number(row["bullet_share"]),
                stage_fps=stages,
                mean_particles=number(row["mean_particles"]),
                tracking_rms_mm=number(row["tracking_rms_mm"]),
                tracking_rms_px=number(row["tracking_rms_px"]),
                reference_drift_mm=number(row["reference_drift_mm"]),
                errors=errors,
                placements=int(row["placements"]),
                node=row.get("node") or "",
            )
        )
    return results


HEADLINE = {
    "turn": "yaw_error_deg",
    "slide": "travel_error_mm",
    "slip": "slip_error_pct",
    "flick": None,
    "two hands": "travel_error_mm",
    "noisy": "yaw_error_deg",
}


def markdown_table(results: Sequence[Result]) -> str:
    """One row per setting and scenario: speed, Bullet's share, errors (over several
    placements: the mean absolute error and, in brackets, the largest)."""
    header = (
        "setting",
        "scenario",
        "frames/s",
        "× real time",
        "Bullet share",
        "particles",
        "tracking RMS (mm / px)",
        "error vs ground truth",
        "drift vs reference (mm)",
    )
    rows = []
    for r in results:
        key = HEADLINE[r.scenario]
        if key is None:
            truth = "—"
        elif f"abs_{key}" in r.errors:
            truth = f"|{key}| {r.errors[f'abs_{key}']:.2f} ({r.errors[f'max_abs_{key}']:.2f})"
        else:
            truth = f"{key} {r.errors[key]:+.2f}"
        rows.append(
            (
                r.setting,
                r.scenario,
                f"{r.fps:.0f}",
                f"{r.realtime:.1f}",
                f"{100 * r.bullet_share:.0f} %",
                f"{r.mean_particles:.0f}",
                f"{r.tracking_rms_mm:.2f} / {r.tracking_rms_px:.2f}",
                truth,
                f"{r.reference_drift_mm:.2f}",
            )
        )
    return pipe_table(header, rows)


def _abs_error(result: Result, key: str) -> float:
    """Mean |error| over the placements (just |error| with one)."""
    return result.errors.get(f"abs_{key}", abs(result.errors[key]))


#: Settings the Pareto plot names even off the front.
PRESET_LABELS = ("default", "reference", "preset:fast", "coarse")


def pareto_png(results: Sequence[Result], path: Path) -> Path:
    """Two panels, one point per setting, speed = the canonical turn's real-time
    factor: its |yaw error| against ground truth, and the mean drift of every
    scenario's final poses against the reference fidelity."""
    from graspenv.plots import pareto_chart, write_png

    settings = list(dict.fromkeys(r.setting for r in results))
    by = {(r.setting, r.scenario): r for r in results}
    kept = [s for s in settings if (s, "turn") in by]
    speed = [by[s, "turn"].realtime for s in kept]
    yaw = [_abs_error(by[s, "turn"], "yaw_error_deg") for s in kept]
    drift = [
        float(np.nanmean([r.reference_drift_mm for r in results if r.setting == s])) for s in kept
    ]
    panels = [
        (
            yaw,
            "Canonical turn: speed against error (front joined)",
            "x real time (60 Hz camera), log scale",
            "|yaw error| (deg), log scale",
        ),
        (
            drift,
            "Every scenario: drift of final poses against the reference fidelity",
            "x real time of the canonical turn, log scale",
            "mean drift (mm), log scale",
        ),
    ]
    images = [
        pareto_chart(
            kept,
            list(zip(speed, error, strict=True)),
            None,
            title,
            x_label,
            y_label,
            log_error=True,
            labelled=PRESET_LABELS,
        )
        for error, title, x_label, y_label in panels
    ]
    return write_png(np.vstack(images), path)


def write_outputs(results: Sequence[Result], out: Path) -> list[Path]:
    """``bench.csv``, ``bench.md`` and ``pareto.png`` in ``out``; the plot only
    when the canonical turn was run (its speed is the plot's axis)."""
    out.mkdir(parents=True, exist_ok=True)
    table = markdown_table(results)
    (out / "bench.md").write_text(table + "\n")
    written = [write_csv(results, out / "bench.csv"), out / "bench.md"]
    if any(r.scenario == "turn" for r in results):
        written.append(pareto_png(results, out / "pareto.png"))
    return written
