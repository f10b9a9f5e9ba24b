"""``graspenv bench``: speed against error.

Every scenario of :data:`SCENARIOS` (graspenv/bench/scenarios.py says what each
plays and measures) runs at every setting of :data:`SETTINGS`
(:func:`run_bench`, :func:`measure`); the results and their CSV, table and plot
are in graspenv/bench/results.py.

Every scenario also gives the contour-point tracking error: for each particle that
continues from one frame to the next, its contour point against where the finger's
true rigid motion takes the previous point (RMS, mm and pixels); and the drift of
the final object poses against the same scenario at the ``reference`` fidelity.

**Placements.** One run of a scenario is one draw of how the hand's edges fall on the
camera's pixels: moving the whole scene by a fraction of a pixel moves the canonical
turn's yaw error by more than half a degree either way. With ``placements`` P > 1
each scenario is played P times, the scene shifted by sub-pixel offsets (the first
unshifted), and every error is the mean over them; ``abs_<error>`` is the mean of
its absolute value and ``max_abs_<error>`` its largest. Setting against setting, only
differences beyond that spread mean anything.

Speed: camera frames per second of :meth:`Simulation.step` (the pipeline; rendering
the synthetic mask is not counted) and of each of its stages, the real-time factor
against the scene's camera rate, and the share of frame time inside Bullet's own
``stepSimulation``. Each frame's stage times are the smallest over ``replays``
runs of the same masks (the speed of a shared machine varies by a third from one
second to the next; the minimum keeps the work, not the neighbours). Before any
timed run, :func:`warm_up` plays every scenario and every setting once untimed: the
first call of each compiled kernel in a process loads it from numba's cache, or
compiles it on a machine's first run, and the frame that pays for it would
otherwise count (measured 2026-12-07 with the cache warm: the first canonical turn
of a process ran at 406 frames a second, the next two at 605 and 590). Each setting
is the default scene with one knob changed (a one-at-a-time sweep) plus the named
presets.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from graspenv.bench.playback import Played
from graspenv.bench.results import (
    Result,
)
from graspenv.bench.scenarios import (
    SCENARIOS,
    Offset,
    placement_offsets,
)
from graspenv.config import FIDELITY_PRESETS, SceneConfig, at_fidelity, load_config

__all__ = [
    "COARSE",
    "PRESET_SETTINGS",
    "QUICK_SCENARIOS",
    "QUICK_SETTINGS",
    "SETTINGS",
    "measure",
    "measure_reference_row",
    "play_task",
    "run_bench",
    "setting_scene",
    "summarise",
    "warm_up",
]

#: The cheapest setting measured, the ``fast`` preset until 2026-12-06; the same as
#: envs_configs/coarse.toml, which says what it costs.
COARSE: dict[str, dict[str, Any]] = {
    "physics": {
        "substeps": 2,
        "substep_travel": 0.002,
        "max_substeps": 16,
        "solver_iterations": 50,
        "reduced_objects": False,
        "contact_erp": 0.08,
        "max_particle_force": 5.0,
    },
    "contacts": {"spacing": 0.006},
}

# -- settings ----------------------------------------------------------------------------


def _knob(section: str, key: str, values: Iterable[Any], fmt: str = "{}") -> dict[str, Any]:
    return {f"{key}={fmt.format(v)}": {section: {key: v}} for v in values}


#: label → section overrides of the default scene: a one-at-a-time sweep.
SETTINGS: dict[str, dict[str, dict[str, Any]]] = {
    "default": {},
    **_knob("surface", "resolution", [(320, 240), (1280, 960)], "{0[0]}x{0[1]}"),
    **_knob("contacts", "spacing", [0.002, 0.003, 0.006], "{:.3f}"),
    **_knob("proxy", "window", [2, 8]),
    **_knob("proxy", "matcher", ["exhaustive", "fast"]),
    **_knob("physics", "substeps", [1, 2, 8]),
    **_knob("physics", "solver_iterations", [10, 25, 100]),
    **_knob("proxy", "stack_layers", [2, 3]),
    "cull=off": {"proxy": {"cull": False}},
    **_knob("proxy", "cull_margin", [0.0, 0.01], "{:.3f}"),
    **_knob("proxy", "method", ["instant", "rigid"]),
    # The presets are played through at_fidelity (setting_scene, PRESET_SETTINGS),
    # which also refines the reference's contour from the scene's own
    # (graspenv/config.py, FIDELITY_PRESETS, says what each holds).
    "reference": FIDELITY_PRESETS["reference"],
    # fast is the default without CCD (a guard, tests/stability): what the guard costs.
    "preset:fast": FIDELITY_PRESETS["fast"],
    "coarse": COARSE,
}

#: The ``--quick`` subset of :data:`SETTINGS` (and of :data:`SCENARIOS` below).
QUICK_SETTINGS = (
    "default",
    "resolution=320x240",
    "spacing=0.006",
    "matcher=fast",
    "substeps=2",
    "solver_iterations=10",
    "method=instant",
    "reference",
)
QUICK_SCENARIOS = ("turn", "slide", "slip", "two hands")


#: The settings that are fidelity presets, played as the environments play them.
PRESET_SETTINGS = {"reference": "reference", "preset:fast": "fast"}


def setting_scene(base: SceneConfig, setting: str) -> SceneConfig:
    """``base`` at a setting of :data:`SETTINGS`: a preset through
    :func:`~graspenv.config.at_fidelity` (the reference's contour refined from the
    scene's own), any other with its overrides merged over it."""
    if setting in PRESET_SETTINGS:
        return at_fidelity(base, PRESET_SETTINGS[setting])
    return base.replace(**SETTINGS[setting])


def _mean_errors(plays: Sequence[Played]) -> dict[str, float]:
    """Each error's mean over the placements; with several, also ``abs_`` and
    ``max_abs_`` (module docstring)."""
    errors: dict[str, float] = {}
    for key in plays[0].errors:
        values = np.array([p.errors[key] for p in plays], dtype=float)
        finite = values[np.isfinite(values)]
        errors[key] = float(finite.mean()) if finite.size else math.nan
        if len(plays) > 1:
            errors[f"abs_{key}"] = float(np.abs(finite).mean()) if finite.size else math.nan
            errors[f"max_abs_{key}"] = float(np.abs(finite).max()) if finite.size else math.nan
    return errors


def measure(
    setting: str,
    scenario: str,
    scene: SceneConfig,
    references: Sequence[Played] | None,
    offsets: Sequence[Offset] = ((0.0, 0.0),),
    replays: int = 1,
) -> tuple[Result, list[Played]]:
    """Play one scenario at one setting, once per placement offset.

    Args:
        setting: the setting's label.
        scenario: a key of :data:`SCENARIOS`.
        scene: the scene at that setting.
        references: the same scenario at the reference fidelity, one run per offset
            (None: no drift figure).
        offsets: the placements (:func:`placement_offsets`).
        replays: timing runs of each (:func:`play`).
    """
    plays = [SCENARIOS[scenario](scene, offset, replays=replays) for offset in offsets]
    return summarise(setting, scenario, scene, plays, references), plays


def play_task(
    scenario: str, scene: SceneConfig, offsets: Sequence[Offset], replays: int
) -> tuple[list[Played], str]:
    """One Ray task of ``graspenv bench --ray``: a scenario at one setting, every
    placement, in one worker (so that its speed is one node's), and that node. The
    worker may be fresh, so the first placement is played once untimed before
    (:func:`warm_up`)."""
    from graspenv import cluster

    SCENARIOS[scenario](scene, offsets[0], replays=1)
    plays = [SCENARIOS[scenario](scene, offset, replays=replays) for offset in offsets]
    return plays, cluster.node()


def summarise(
    setting: str,
    scenario: str,
    scene: SceneConfig,
    plays: Sequence[Played],
    references: Sequence[Played] | None,
    node: str = "",
) -> Result:
    """The row of one scenario at one setting from its plays (see :func:`measure`);
    ``node`` labels where a Ray task played them."""
    frames = sum(p.frames for p in plays)
    stages: dict[str, float] = {}
    for played in plays:
        for stage, seconds in played.stage_seconds.items():
            stages[stage] = stages.get(stage, 0.0) + seconds
    total = sum(stages.values())
    fps = frames / total
    camera = scene.surface.fps
    metres_per_pixel = scene.surface.size[0] / scene.surface.resolution[0]
    squares = [e for p in plays for e in p.tracking_sq]
    rms = math.sqrt(float(np.mean(squares))) if squares else math.nan
    drift = math.nan
    # The slip run stops when the box slips, so its final pose is not comparable.
    if references is not None and scenario != "slip":
        drift = 1000 * float(
            np.mean(
                [
                    max(
                        float(np.linalg.norm(p.final[name][:2] - r.final[name][:2]))
                        for name in p.final
                    )
                    for p, r in zip(plays, references, strict=True)
                ]
            )
        )
    return Result(
        setting=setting,
        scenario=scenario,
        frames=frames,
        fps=fps,
        realtime=fps / camera,
        bullet_share=stages["physics"] / total,
        stage_fps={k: frames / max(v, 1e-12) for k, v in stages.items()},
        mean_particles=float(np.mean([n for p in plays for n in p.particles])),
        tracking_rms_mm=1000 * rms,
        tracking_rms_px=rms / metres_per_pixel,
        reference_drift_mm=drift,
        errors=_mean_errors(plays),
        placements=len(plays),
        node=node,
    )


def warm_up(
    order: Sequence[str],
    scenarios: Sequence[str],
    base: SceneConfig,
    progress: Callable[[str], None] | None = None,
) -> None:
    """Play every scenario at the first setting of ``order``, and the first scenario at
    every other setting, once each, unplaced and untimed (module docstring): between
    them they reach the compiled kernels that each scenario and each setting bring,
    so that the timed runs do not pay their first load or compile. Nothing is kept:
    each play builds its own simulation, so the runs after are the same to the bit."""
    if not scenarios:
        return
    if progress is not None:
        progress("warming up: every scenario and setting once, untimed")
    first = setting_scene(base, order[0])
    for scenario in scenarios:
        SCENARIOS[scenario](first, (0.0, 0.0), replays=1)
    for setting in order[1:]:
        SCENARIOS[scenarios[0]](setting_scene(base, setting), (0.0, 0.0), replays=1)


def run_bench(
    settings: Sequence[str],
    scenarios: Sequence[str],
    config: str | SceneConfig | None = None,
    progress: Callable[[str], None] | None = None,
    placements: int = 1,
    replays: int = 1,
    ray: bool = False,
    address: str | None = None,
) -> list[Result]:
    """Every scenario at the reference fidelity first, then at every setting.

    Args:
        settings: keys of :data:`SETTINGS`.
        scenarios: keys of :data:`SCENARIOS`.
        config: the base scene (a file, a config or None for the built-in default).
        progress: called with a line before each run.
        placements: sub-pixel placements per scenario and setting (module docstring);
            the same offsets, from the base scene's pixel size, for every setting.
        replays: timing runs of every scenario; speeds are per-frame minimums over
            them (:func:`play`); errors come from the first. Every timed run comes
            after :func:`warm_up`.
        ray, address: play each (setting, scenario) as one Ray task
            (:func:`play_task`) on a local instance or the cluster at ``address``.
            The errors are the local run's; each row's speed is one task's on one
            node, named in its ``node`` column (timings from different machines are
            not comparable).
    """
    for name in settings:
        if name not in SETTINGS:
            raise ValueError(f"unknown setting {name!r}; expected one of {list(SETTINGS)}")
    for name in scenarios:
        if name not in SCENARIOS:
            raise ValueError(f"unknown scenario {name!r}; expected one of {list(SCENARIOS)}")
    if placements < 1:
        raise ValueError(f"placements must be >= 1, got {placements}")
    base = load_config(config)
    offsets = placement_offsets(placements, base)
    references: dict[str, list[Played]] = {}
    results = []
    order = ["reference"] + [s for s in settings if s != "reference"]
    if ray or address is not None:
        return _run_on_ray(order, settings, scenarios, base, offsets, replays, address)
    warm_up(order, scenarios, base, progress)
    total = len(order) * len(scenarios)
    done = 0
    for setting in order:
        scene = setting_scene(base, setting)
        for scenario in scenarios:
            done += 1
            if progress is not None:
                progress(f"[{done}/{total}] {scenario} at {setting}")
            result, plays = measure(
                setting, scenario, scene, references.get(scenario), offsets, replays
            )
            if setting == "reference":
                references[scenario] = plays
                result = measure_reference_row(result)
            if setting in settings:
                results.append(result)
    return results


def _run_on_ray(
    order: Sequence[str],
    settings: Sequence[str],
    scenarios: Sequence[str],
    base: SceneConfig,
    offsets: Sequence[Offset],
    replays: int,
    address: str | None,
) -> list[Result]:
    from graspenv import cluster

    cluster.connect(address)
    jobs = [(setting, scenario) for setting in order for scenario in scenarios]
    calls = [
        (scenario, setting_scene(base, setting), offsets, replays) for setting, scenario in jobs
    ]
    played = dict(zip(jobs, cluster.run_tasks(play_task, calls, "bench runs"), strict=True))
    results = []
    for setting, scenario in jobs:
        plays, node = played[setting, scenario]
        references = None if setting == "reference" else played["reference", scenario][0]
        scene = setting_scene(base, setting)
        result = summarise(setting, scenario, scene, plays, references, node)
        if setting == "reference":
            result = measure_reference_row(result)
        if setting in settings:
            results.append(result)
    return results


def measure_reference_row(result: Result) -> Result:
    """The reference against itself drifts by 0 by definition (slip: not measured)."""
    drift = math.nan if result.scenario == "slip" else 0.0
    return Result(**{**result.__dict__, "reference_drift_mm": drift})
