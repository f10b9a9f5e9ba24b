"""``graspenv bench --grid``: accuracy across the grasp space.

The canonical scene is one grasp. The grid plays the same two-finger grasp over the
space around it, each map sweeping two of its parameters with the rest at the
canonical values (:data:`BASE_CELL`):

- boxes and upright cylinders, footprint (side or diameter) 3–12 cm against mass
  5 g–2 kg;
- box height 1–8 cm against squeeze depth 1–6 mm;
- object friction 0.3–1 against fingertip radius 5–12 mm.

The maps miss the corners where several parameters are extreme together, so
``graspenv bench --grid --sample N`` plays instead N cells drawn from the whole
space at once (:func:`sampled`, :data:`SPACE`).

Every cell sits at its own place on the table and its own sub-pixel phase (seeded),
so no cell shares the canonical scene's pixel grid. Each cell plays three runs
through the whole pipeline and measures them against ground truth, the ideal rigid
grasp:

- ``turn``: squeeze and turn the pair 90° in 1.5 s. Error: the object's yaw against
  the fingers' 90°, degrees.
- ``slide``: squeeze and slide the pair 10 cm across the grip. Error: the distance
  between where the object ends and where the rigid grasp takes it (lateral drift
  included), as a share of the travel, %; and its two parts, along the travel and
  across it.
- ``slip``: squeeze and hold, then push across the grip along the contacts' line
  (so it cannot tip the object over them), the push growing by :data:`SLIP_RAMP` of
  Coulomb's prediction a second, until it slips: slides from under every gripping
  particle (:func:`graspenv.bench.scenarios.push_until_slip`). Error: the push at
  slip against ``μ_f·ΣN_fingers + μ_t·N_table`` with the normal forces of the
  settled grip, %; beside it (not a target), against the same with the fingers'
  normal force just before the slip, which the grip's give can lower. A finger's
  normal force is the resultant of its particles'
  (:meth:`~graspenv.physics.reports.ContactReport.grip_normal_force`): round a
  curved side their parts across the contact cancel.

**Margins.** Whether a rigid pair of fingertips could hold the grasp at all is
Coulomb's law on the normal force the grip actually exerts (measured, mean over the
motion): with μ_f and μ_t Bullet's finger–object and table–object coefficients (the
products of the two bodies'), N the fingers' normal force (as for the slip), m g the weight, w
the distance between the two contacts and r_eff the mean distance of the footprint
from its centre (0.383 × side for a square, 2/3 radius for a disc, uniform
pressure),

- slide margin = μ_f N / (μ_t m g): the grip's friction over the table's;
- turn margin = μ_f N w / (2 μ_t m g r_eff): the grip's couple over the table's
  torque.

A cell is counted against the targets (turn ≤ :data:`TURN_TARGET_DEG`, slide ≤
:data:`SLIDE_TARGET_PCT`) only where its margin is at least :data:`MARGIN`. Two,
because the uniform-pressure torque is a best case: a squeezed object rocks onto
one edge, and with all its weight at the corners a square's r_eff is 0.707 × side,
1.85 × the uniform figure; and the normal force varies by ±15 % over a motion.
Cells below the margin are drawn hatched and listed, not counted.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from graspenv.bench.interactions import FINGER_RADIUS, pinch, with_objects
from graspenv.bench.jobs import collect_jobs
from graspenv.bench.playback import Played, play
from graspenv.bench.results import pipe_table, write_rows
from graspenv.bench.scenarios import push_until_slip
from graspenv.config import ObjectConfig, SceneConfig, at_fidelity, load_config
from graspenv.geometry import tilt_angle, yaw_of, yaw_step
from graspenv.plots import HeatPanel, heat_maps, sorted_errors, write_png
from graspenv.simulation import Simulation
from graspenv.surface.noise import SensorNoise

__all__ = [
    "BASE_CELL",
    "MAPS",
    "Cell",
    "CellResult",
    "GridMap",
    "grasp_run",
    "heat_map_png",
    "measure_cell",
    "run_grid",
    "slip_run",
]

TURN_TARGET_DEG = 1.0
SLIDE_TARGET_PCT = 2.0
SLIP_TARGET_PCT = 5.0
#: The slip run's push grows by this share of Coulomb's prediction a second (a
#: faster ramp, 1 a second, let a flat box slip 25 % early; at 0.3 it is within 1 %).
SLIP_RAMP = 0.3
MARGIN = 2.0
GRAVITY = 9.81
TURN = math.pi / 2
SLIDE = 0.10  # metres, along +y (across the grip)


@dataclass(frozen=True)
class Cell:
    """One grasp of the grid (SI units)."""

    shape: str = "box"  # "box" or "cylinder" (upright)
    footprint: float = 0.06  # side of the square or diameter of the disc, metres
    height: float = 0.03
    mass: float = 0.2
    friction: float = 0.5  # the object's; Bullet multiplies it by the other body's
    depth: float = 0.003  # how far each fingertip presses into the object
    finger_radius: float = FINGER_RADIUS
    position: tuple[float, float] = (0.0, 0.0)  # on the table, metres

    def object(self) -> ObjectConfig:
        size = (
            (self.footprint, self.footprint, self.height)
            if self.shape == "box"
            else (self.footprint / 2, self.height)
        )
        return ObjectConfig(
            name="box",
            shape=self.shape,  # type: ignore[arg-type]
            size=size,
            mass=self.mass,
            friction=self.friction,
            position=self.position,
        )

    def label(self) -> str:
        """The object in words (progress lines): shape, footprint x height, mass."""
        return (
            f"{self.shape} {100 * self.footprint:g} cm x {100 * self.height:g} cm,"
            f" {1000 * self.mass:g} g"
        )

    @property
    def mean_radius(self) -> float:
        """Mean distance of the footprint from its centre, metres (uniform pressure)."""
        if self.shape == "box":
            # (1/3)(√2 + ln(1 + √2)) / 2 × side, the mean distance in a unit square.
            return 0.3826 * self.footprint
        return self.footprint / 3.0


BASE_CELL = Cell()


@dataclass(frozen=True)
class GridMap:
    """Two parameters of :class:`Cell` swept against each other, the rest at ``base``."""

    name: str
    title: str
    x: str
    x_values: tuple[float, ...]
    y: str
    y_values: tuple[float, ...]
    base: Cell = BASE_CELL

    def cells(self) -> list[Cell]:
        swept: list[dict[str, Any]] = [
            {self.x: xv, self.y: yv} for yv in self.y_values for xv in self.x_values
        ]
        return [replace(self.base, **values) for values in swept]


_FOOTPRINTS = (0.03, 0.045, 0.06, 0.09, 0.12)
_MASSES = (0.005, 0.02, 0.1, 0.5, 2.0)
MAPS: tuple[GridMap, ...] = (
    GridMap("boxes", "boxes: footprint x mass", "footprint", _FOOTPRINTS, "mass", _MASSES),
    GridMap(
        "cylinders",
        "upright cylinders: diameter x mass",
        "footprint",
        _FOOTPRINTS,
        "mass",
        _MASSES,
        replace(BASE_CELL, shape="cylinder"),
    ),
    GridMap(
        "height",
        "boxes: height x squeeze depth",
        "height",
        (0.01, 0.02, 0.04, 0.06, 0.08),
        "depth",
        (0.001, 0.002, 0.003, 0.0045, 0.006),
    ),
    GridMap(
        "friction",
        "boxes: friction x fingertip radius",
        "friction",
        (0.3, 0.5, 0.7, 1.0),
        "finger_radius",
        (0.005, 0.007, 0.009, 0.012),
    ),
)


def placed(cells: Sequence[Cell], seed: int = 0) -> list[Cell]:
    """The cells, each moved to its own seeded place on the table: anywhere the
    slide stays on it, at a continuous (so sub-pixel) offset."""
    rng = np.random.default_rng(seed)
    out = []
    for cell in cells:
        x = float(rng.uniform(-0.12, 0.12))
        y = float(rng.uniform(-0.12, 0.0))
        out.append(replace(cell, position=(x, y)))
    return out


#: The grasp space the maps cut through: each parameter's range over the maps'
#: cells (the mass drawn on a log scale). :func:`sampled` draws from all of them at
#: once.
SPACE: Mapping[str, tuple[float, float]] = MappingProxyType(
    {
        name: (
            min(getattr(c, name) for m in MAPS for c in m.cells()),
            max(getattr(c, name) for m in MAPS for c in m.cells()),
        )
        for name in ("footprint", "height", "mass", "friction", "depth", "finger_radius")
    }
)
#: The map name of :func:`sampled` cells.
SAMPLE = "sample"


def sampled(count: int, seed: int = 0) -> list[Cell]:
    """``count`` cells drawn at random from the whole of :data:`SPACE`, every
    parameter at once (the maps vary two at a time), half boxes and half upright
    cylinders on average, each at its own place on the table (:func:`placed`).

    Args:
        count: how many cells, at least 1.
        seed: the draw's seed; the same seed gives the same cells, and a smaller
            count the first of them.

    Raises:
        ValueError: ``count`` is below 1.
    """
    if count < 1:
        raise ValueError(f"a sample needs at least 1 cell, got {count}")
    rng = np.random.default_rng(seed)
    cells = []
    for _ in range(count):
        values: dict[str, Any] = {
            name: float(
                math.exp(rng.uniform(math.log(low), math.log(high)))
                if name == "mass"
                else rng.uniform(low, high)
            )
            for name, (low, high) in SPACE.items()
        }
        shape = "box" if rng.random() < 0.5 else "cylinder"
        cells.append(replace(Cell(shape=shape), **values))
    return placed(cells, seed + 1)


@dataclass
class CellResult:
    """What one cell measured (NaN where a run gave no figure)."""

    cell: Cell
    map: str = ""
    grip_normal_n: float = math.nan
    turn_error_deg: float = math.nan
    slide_error_pct: float = math.nan
    slip_error_pct: float = math.nan
    #: The slip against Coulomb's force from the normal force just before it (the
    #: grip's give round a curved side costs normal force). Not a target:
    #: ``slip_error_pct`` is.
    slip_error_then_pct: float = math.nan
    turn_margin: float = math.nan
    slide_margin: float = math.nan
    max_tilt_deg: float = math.nan
    #: The slip against Coulomb's force at its onset, the push midway between the
    #: last one held and the first not held, at the settled normal force and at the
    #: force just before it (the gross slip, ``slip_error_pct``, comes a frame or
    #: two later: :data:`~graspenv.bench.scenarios.SLIP_ONSET_SPEED`). Not targets.
    slip_onset_error_pct: float = math.nan
    slip_onset_then_pct: float = math.nan
    #: How far beyond Coulomb's force the tilt of Bullet's contact normals holds the
    #: object against the push just before the slip, per cent of Coulomb's force
    #: (:func:`~graspenv.bench.scenarios.normal_tilt_push`): the engine's part of
    #: ``slip_error_pct``, not the model's. Not a target.
    slip_normal_tilt_pct: float = math.nan
    #: The slide's error in two parts, per cent of the travel, signed: along it
    #: (positive past where the hand stopped: the object's overshoot as the hand
    #: stops, what the grip's give lets through) and across it, along the grip's
    #: axis (where the pinch left it between the fingertips' rendered outlines).
    #: ``slide_error_pct`` is their length. Not targets.
    slide_along_pct: float = math.nan
    slide_across_pct: float = math.nan
    #: How steady the settled grip of the slip run is: the fingers' normal force's
    #: standard deviation over its mean across the settled frames, per cent. Not a
    #: target (docs/accuracy.md, "The slide's last tenth of a millimetre": a grip of many
    #: sub-steps at Bullet's per-step contact ERP jitters).
    grip_normal_spread_pct: float = math.nan

    @property
    def slip_untilted_pct(self) -> float:
        """The slip against Coulomb's force with the tilt of Bullet's normals taken
        out (``slip_error_pct`` less ``slip_normal_tilt_pct``): the model's own
        error, as near as the engine lets it be measured. Not a target."""
        return self.slip_error_pct - self.slip_normal_tilt_pct

    @property
    def turn_counted(self) -> bool:
        return self.turn_margin >= MARGIN

    @property
    def slide_counted(self) -> bool:
        return self.slide_margin >= MARGIN

    @property
    def turn_ok(self) -> bool:
        return abs(self.turn_error_deg) <= TURN_TARGET_DEG

    @property
    def slide_ok(self) -> bool:
        return abs(self.slide_error_pct) <= SLIDE_TARGET_PCT

    def row(self) -> dict[str, Any]:
        row = run_row(self, "map")
        row["turn_counted"] = self.turn_counted
        row["slide_counted"] = self.slide_counted
        return row


def cell_row(cell: Cell) -> dict[str, Any]:
    """A cell as CSV columns: its fields, the position as ``x`` and ``y``."""
    row = asdict(cell)
    row["x"], row["y"] = row.pop("position")
    return row


def run_row(run: Any, *first: str) -> dict[str, Any]:
    """A dataclass that measured one cell (field ``cell``), as CSV columns: the fields
    named in ``first``, the cell's columns (:func:`cell_row`), then its other fields
    in order."""
    row: dict[str, Any] = {name: getattr(run, name) for name in first}
    row.update(cell_row(run.cell))
    skip = (*first, "cell")
    row.update({f.name: getattr(run, f.name) for f in fields(run) if f.name not in skip})
    return row


def cell_from_row(row: Mapping[str, str]) -> Cell:
    """The cell of a CSV row written from :func:`cell_row`."""
    numbers = {
        f.name: float(row[f.name]) for f in fields(Cell) if f.name not in ("shape", "position")
    }
    return Cell(shape=row["shape"], position=(float(row["x"]), float(row["y"])), **numbers)


def _coefficients(base: SceneConfig, cell: Cell) -> tuple[float, float]:
    """Bullet's finger-object and table-object friction (products of the bodies')."""
    return base.proxy.particle_friction * cell.friction, base.physics.table_friction * cell.friction


def grasp_run(
    base: SceneConfig,
    cell: Cell,
    motion: str,
    noise: SensorNoise | None = None,
    noise_seed: int = 0,
) -> tuple[NDArray[np.float64], float, float, float]:
    """Squeeze and turn (or slide) the pair, the masks seen through ``noise`` if
    given; the object's final (x, y, z, yaw), how far it turned (radians,
    unwrapped), the mean finger normal force over the motion (N) and the largest
    tilt (degrees)."""
    obj = cell.object()
    if motion == "turn":
        kwargs: dict[str, Any] = {"turn": TURN, "turn_frames": 90, "slide_frames": 0}
    else:
        kwargs = {"slide": (0.0, SLIDE), "turn_frames": 0, "slide_frames": 90}
    script = pinch(obj, cell.depth, cell.finger_radius, hold_frames=15, **kwargs)
    moving = {i for name, frames in script.phase_ranges() if name == motion for i in frames}
    normal: list[float] = []
    state = {"yaw": 0.0, "last": obj.yaw, "tilt": 0.0}

    def each(sim: Simulation, index: int, played: Played) -> bool:
        _, q = sim.object_pose("box")
        now = yaw_of(q)
        state["yaw"] += yaw_step(now, state["last"])
        state["last"] = now
        state["tilt"] = max(state["tilt"], math.degrees(tilt_angle(q)))
        if index in moving:
            report = sim.contact_report("box")
            normal.append(report.grip_normal_force(sim.particles_by_contact()))
        return False

    played = play(with_objects(base, obj), script, ["box"], (), noise, each, noise_seed=noise_seed)
    mean_normal = float(np.mean(normal)) if normal else 0.0
    return played.final["box"], state["yaw"], mean_normal, state["tilt"]


def measure_cell(cell: Cell, base: SceneConfig | None = None, map_name: str = "") -> CellResult:
    """Play a cell's turn, slide and slip runs and measure them (module docstring)."""
    base = load_config(None) if base is None else base
    mu_f, mu_t = _coefficients(base, cell)
    weight = cell.mass * GRAVITY
    result = CellResult(cell, map_name)

    _, turned, turn_normal, turn_tilt = grasp_run(base, cell, "turn")
    result.turn_error_deg = math.degrees(turned - TURN)
    # The contacts are the fingertips' on the two faces: the footprint apart.
    result.turn_margin = (
        mu_f * turn_normal * cell.footprint / (2.0 * mu_t * weight * cell.mean_radius)
    )

    final, _, slide_normal, slide_tilt = grasp_run(base, cell, "slide")
    x, y = final[:2]
    ideal = (cell.position[0], cell.position[1] + SLIDE)
    result.slide_along_pct = 100.0 * (y - ideal[1]) / SLIDE
    result.slide_across_pct = 100.0 * (x - ideal[0]) / SLIDE
    result.slide_error_pct = math.hypot(result.slide_along_pct, result.slide_across_pct)
    result.slide_margin = mu_f * slide_normal / (mu_t * weight)
    result.grip_normal_n = 0.5 * (turn_normal + slide_normal)
    result.max_tilt_deg = max(turn_tilt, slide_tilt)

    slipped = slip_run(base, cell).errors
    result.slip_error_pct = slipped["slip_error_pct"]
    result.slip_error_then_pct = slipped["slip_error_then_pct"]
    result.slip_onset_error_pct = slipped["slip_onset_error_pct"]
    result.slip_onset_then_pct = slipped["slip_onset_then_pct"]
    result.slip_normal_tilt_pct = slipped["slip_normal_tilt_pct"]
    result.grip_normal_spread_pct = slipped["grip_normal_spread_pct"]
    return result


def slip_run(base: SceneConfig, cell: Cell) -> Played:
    """Squeeze the cell's object, then push it across the grip, the push growing by
    :data:`SLIP_RAMP` of Coulomb's prediction a second, until it slips
    (:func:`~graspenv.bench.scenarios.push_until_slip`)."""
    # Pushed along the contacts' line: the particles' centres are a radius up.
    return push_until_slip(
        base,
        cell.object(),
        cell.depth,
        relative_rate=SLIP_RAMP,
        ramp_frames=round(2.0 / SLIP_RAMP * base.surface.fps),
        height=base.proxy.particle_radius,
        finger_radius=cell.finger_radius,
    )


def base_scene(config: str | None = None, preset: str = "default") -> SceneConfig:
    """The scene file (or the built-in default) with a fidelity preset applied."""
    return at_fidelity(load_config(config), preset)


def _measure(job: tuple[Cell, str, str | None, str]) -> CellResult:
    cell, map_name, config, preset = job
    return measure_cell(cell, base_scene(config, preset), map_name)


def grid_jobs(maps: Sequence[GridMap], seed: int = 0) -> list[tuple[Cell, str]]:
    """Every map's cells, placed (:func:`placed`), with their map's name."""
    jobs = []
    for index, grid_map in enumerate(maps):
        for cell in placed(grid_map.cells(), seed + index):
            jobs.append((cell, grid_map.name))
    return jobs


def run_grid(
    maps: Sequence[GridMap] = MAPS,
    config: str | None = None,
    progress: Callable[[str], None] | None = None,
    workers: int = 1,
    seed: int = 0,
    preset: str = "default",
    sample: int = 0,
) -> list[CellResult]:
    """Measure every cell of ``maps`` (in ``workers`` processes) on the scene file
    ``config`` (or the built-in default) at a fidelity ``preset``; with ``sample``,
    that many cells drawn from the whole space instead (:func:`sampled`)."""
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if sample < 0:
        raise ValueError(f"sample must be at least 0, got {sample}")
    base_scene(config, preset)  # a bad file or preset fails here, not in a worker
    chosen = [(c, SAMPLE) for c in sampled(sample, seed)] if sample else grid_jobs(maps, seed)
    jobs = [(cell, name, config, preset) for cell, name in chosen]
    return collect_jobs(_measure, jobs, workers, progress, _describe)


def _describe(result: CellResult) -> str:
    c = result.cell
    return (
        f"{result.map}: {c.label()}, mu {c.friction:g},"
        f" depth {1000 * c.depth:g} mm, finger {1000 * c.finger_radius:g} mm:"
        f" turn {result.turn_error_deg:+.2f} deg, slide {result.slide_error_pct:.2f} %,"
        f" slip {result.slip_error_pct:+.1f} %, margins {result.turn_margin:.1f}"
        f"/{result.slide_margin:.1f}"
    )


# -- outputs --------------------------------------------------------------------------


def write_csv(results: Sequence[CellResult], path: Path) -> Path:
    return write_rows([r.row() for r in results], path)


def read_csv(path: Path) -> list[CellResult]:
    """Results written by :func:`write_csv` (a column an older run lacks is NaN)."""
    numbers = {f.name for f in fields(CellResult)} - {"cell", "map"}
    with path.open() as f:
        return [
            CellResult(
                cell_from_row(row), row["map"], **{k: float(row.get(k, "nan")) for k in numbers}
            )
            for row in csv.DictReader(f)
        ]


def summary(results: Sequence[CellResult]) -> str:
    """Markdown: per map, the counted cells meeting each target, the worst counted
    errors, and the cells not counted."""
    header = (
        "map",
        "turn ≤ 1° (counted)",
        "worst turn",
        "slide ≤ 2 % (counted)",
        "worst slide",
        "slip within 5 %",
        "worst slip",
        "slip within 5 % of the force then",
        "slip within 5 %, Bullet's normal tilt out",
        "not counted",
    )
    table = []
    groups: dict[str, list[CellResult]] = {}
    for r in results:
        groups.setdefault(r.map, []).append(r)
    groups["all"] = list(results)
    for name, rows in groups.items():
        turns = [r for r in rows if r.turn_counted]
        slides = [r for r in rows if r.slide_counted]
        slips = [r for r in rows if math.isfinite(r.slip_error_pct)]
        worst_turn = max((abs(r.turn_error_deg) for r in turns), default=math.nan)
        worst_slide = max((abs(r.slide_error_pct) for r in slides), default=math.nan)
        worst_slip = max((abs(r.slip_error_pct) for r in slips), default=math.nan)
        uncounted = sum(1 for r in rows if not (r.turn_counted and r.slide_counted))
        within = sum(abs(r.slip_error_pct) <= SLIP_TARGET_PCT for r in slips)
        thens = [r for r in slips if math.isfinite(r.slip_error_then_pct)]
        within_then = sum(abs(r.slip_error_then_pct) <= SLIP_TARGET_PCT for r in thens)
        untilted = [r for r in slips if math.isfinite(r.slip_untilted_pct)]
        within_untilted = sum(abs(r.slip_untilted_pct) <= SLIP_TARGET_PCT for r in untilted)
        table.append(
            (
                name,
                f"{sum(r.turn_ok for r in turns)}/{len(turns)}",
                f"{worst_turn:.2f}°",
                f"{sum(r.slide_ok for r in slides)}/{len(slides)}",
                f"{worst_slide:.2f} %",
                f"{within}/{len(rows)}",
                f"{worst_slip:.1f} %",
                f"{within_then}/{len(rows)}" if thens else "–",  # an older grid.csv
                f"{within_untilted}/{len(rows)}" if untilted else "–",
                uncounted,
            )
        )
    return pipe_table(header, table)


def _fmt(name: str, value: float) -> str:
    if name == "mass":
        return f"{1000 * value:g} g"
    if name in ("footprint", "height"):
        return f"{100 * value:g} cm"
    if name in ("depth", "finger_radius"):
        return f"{1000 * value:g} mm"
    return f"{value:g}"


_PANELS = (
    ("turn_error_deg", "turn error (deg)", TURN_TARGET_DEG, "turn_counted"),
    ("slide_error_pct", "slide error (% of travel)", SLIDE_TARGET_PCT, "slide_counted"),
    ("slip_error_pct", "slip vs Coulomb (%)", SLIP_TARGET_PCT, ""),
)


def heat_map_png(grid_map: GridMap, results: Sequence[CellResult], path: Path) -> Path:
    """:func:`heat_map_image` written to ``path``."""
    return write_png(heat_map_image(grid_map, results), path)


def heat_map_image(grid_map: GridMap, results: Sequence[CellResult]) -> NDArray[np.uint8]:
    """One picture per map: a panel per error, each cell coloured by its |error| over
    the target (green under, red at twice), its value printed; hatched: not counted
    (margin under :data:`MARGIN`)."""
    by_key = {(getattr(r.cell, grid_map.x), getattr(r.cell, grid_map.y)): r for r in results}
    shape = (len(grid_map.y_values), len(grid_map.x_values))
    panels = []
    for key, label, target, counted in _PANELS:
        values, hatched = np.full(shape, math.nan), np.zeros(shape, bool)
        for j, yv in enumerate(grid_map.y_values):
            for i, xv in enumerate(grid_map.x_values):
                r = by_key.get((xv, yv))
                if r is not None:
                    values[j, i] = float(getattr(r, key))
                    hatched[j, i] = bool(counted) and not getattr(r, counted)
        panels.append(HeatPanel(label, values, target, hatched))
    return heat_maps(
        grid_map.title,
        panels,
        [_fmt(grid_map.x, v) for v in grid_map.x_values],
        [_fmt(grid_map.y, v) for v in grid_map.y_values],
        grid_map.x.replace("_", " "),
        grid_map.y.replace("_", " "),
        note=f"green: under target, red: twice it; hatched: margin < {MARGIN:g}, not counted",
    )


def sample_image(results: Sequence[CellResult]) -> NDArray[np.uint8]:
    """The sampled cells' errors, boxes and cylinders apart, each sorted (so the share
    of cells beyond a target reads off the x axis); the turn and slide of counted
    cells only."""
    panels = []
    for key, label, target, counted in _PANELS:
        series = {
            plural: [
                float(getattr(r, key))
                for r in results
                if r.cell.shape == shape and (not counted or getattr(r, counted))
            ]
            for plural, shape in (("boxes", "box"), ("cylinders", "cylinder"))
        }
        panels.append((label, series, target))
    return sorted_errors(
        f"{len(results)} grasps drawn from the whole grasp space",
        panels,
        note=f"dashed: the target; turn and slide: cells of margin >= {MARGIN:g} only",
    )


def write_outputs(
    results: Sequence[CellResult], out: Path, maps: Sequence[GridMap] = MAPS
) -> Iterator[Path]:
    yield write_csv(results, out / "grid.csv")
    md = out / "grid.md"
    md.write_text(summary(results) + "\n")
    yield md
    panels = []
    for grid_map in maps:
        rows = [r for r in results if r.map == grid_map.name]
        if rows:
            image = heat_map_image(grid_map, rows)
            panels.append(image)
            yield write_png(image, out / f"grid_{grid_map.name}.png")
    rows = [r for r in results if r.map == SAMPLE]
    if rows:
        yield write_png(sample_image(rows), out / "grid_sample.png")
    if panels:
        # All maps in one picture for the README.
        width = max(p.shape[1] for p in panels)
        stacked = np.vstack(
            [
                np.pad(p, ((0, 0), (0, width - p.shape[1]), (0, 0)), constant_values=255)
                for p in panels
            ]
        )
        yield write_png(stacked, out / "grid.png")
