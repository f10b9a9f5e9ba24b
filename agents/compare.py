"""``graspenv compare``: the strategy benchmark.

Runs agents over environments on the same seeds and writes ``compare.md`` (a
Markdown table), ``compare.csv`` (the same numbers) and ``compare.png`` (bar charts
of success, with 95 % intervals, and of grasp quality, strategy by task). An agent
runs on the environments it applies to: a scripted strategy or a learned policy on
the one it was written or trained for (unless environments are named explicitly
with ``--env``), ``random`` and ``still`` on every one. Jobs run in parallel, one per core.
"""

from __future__ import annotations

import csv
import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import graspenv
from graspenv.plots import bar_chart, write_png

from .evaluate import evaluate, summary_table
from .loading import check_env_id, load_agent
from .scripted import STRATEGIES

__all__ = ["POLICIES", "CompareResult", "compare", "default_agents"]

#: Learned policies shipped with the repository (``graspenv train`` run folders,
#: trimmed to the model, normalisation, run record and learning curve).
POLICIES = Path(__file__).parent / "policies"


def default_agents() -> list[str]:
    """Every scripted strategy, every shipped policy, and the two floors: random
    actions and a still hand."""
    shipped = sorted(str(p) for p in POLICIES.glob("*") if (p / "run.json").is_file())
    return [f"scripted:{name}" for name in STRATEGIES] + shipped + ["random", "still"]


@dataclass(frozen=True)
class CompareResult:
    summaries: tuple[dict[str, Any], ...]
    table: str
    files: tuple[Path, ...]


def _job(env_id: str, spec: str, seeds: Sequence[int]) -> dict[str, Any]:
    return evaluate(env_id, load_agent(spec, seeds[0]), seeds).summary()


def plan(env_ids: Sequence[str] | None, specs: Sequence[str] | None) -> list[tuple[str, str]]:
    """The (environment, agent spec) pairs to run, checking every name first."""
    for env_id in env_ids or ():
        check_env_id(env_id)
    explicit = bool(env_ids)
    envs = list(env_ids or graspenv.ENV_IDS)
    pairs = []
    for spec in specs or default_agents():
        agent = load_agent(spec)
        for env_id in envs:
            if agent.home is None or agent.home == env_id or (explicit and specs):
                pairs.append((env_id, spec))
    if not pairs:
        raise ValueError("no agent applies to the chosen environments")
    return pairs


def compare(
    env_ids: Sequence[str] | None,
    specs: Sequence[str] | None,
    episodes: int,
    first_seed: int,
    out: Path,
    progress: Callable[[str], None] | None = None,
    workers: int | None = None,
    ray: bool = False,
    address: str | None = None,
    batch: int | None = None,
) -> CompareResult:
    """Run the benchmark and write its files into ``out``: in ``workers`` local
    processes, one (environment, agent) pair each, or with ``ray`` as batches of
    episodes on Ray (:mod:`graspenv_agents.distributed`; a local instance, or the
    cluster at ``address``; ``batch`` episodes a task), which gives the same table."""
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    pairs = plan(env_ids, specs)
    seeds = list(range(first_seed, first_seed + episodes))
    results: dict[tuple[str, str], dict[str, Any]] = {}
    if ray or address is not None:
        from .distributed import BATCH, evaluations

        found, nodes = evaluations(
            pairs, seeds, address=address, batch=batch or BATCH, num_cpus=workers
        )
        results = {pair: evaluation.summary() for pair, evaluation in found.items()}
        if progress is not None:
            progress(f"{len(pairs)} pairs × {episodes} episodes on {len(nodes)} Ray node(s)")
    elif (processes := workers or min(len(os.sched_getaffinity(0)), len(pairs))) <= 1:
        for i, (env_id, spec) in enumerate(pairs):
            results[env_id, spec] = _job(env_id, spec, seeds)
            _report(progress, i + 1, len(pairs), results[env_id, spec])
    else:
        # Spawned, not forked: a worker forked after torch has started its threads
        # (loading a learned policy while planning does) can hang forever.
        with ProcessPoolExecutor(
            processes, mp_context=multiprocessing.get_context("spawn")
        ) as pool:
            futures = {pool.submit(_job, e, s, seeds): (e, s) for e, s in pairs}
            for i, future in enumerate(as_completed(futures)):
                results[futures[future]] = future.result()
                _report(progress, i + 1, len(pairs), results[futures[future]])
    # By environment, then in plan order (the sort is stable).
    summaries = tuple(results[pair] for pair in sorted(pairs, key=lambda p: p[0]))
    return CompareResult(summaries, *write(summaries, out, episodes))


def _report(
    progress: Callable[[str], None] | None, done: int, total: int, s: dict[str, Any]
) -> None:
    if progress is not None:
        progress(f"[{done}/{total}] {s['agent']} on {s['env_id']}: {s['success_rate']:.0%} success")


def write(
    summaries: Sequence[dict[str, Any]], out: Path, episodes: int
) -> tuple[str, tuple[Path, ...]]:
    """``compare.md``, ``compare.csv`` and ``compare.png``."""
    out.mkdir(parents=True, exist_ok=True)
    table = summary_table(summaries)
    (out / "compare.md").write_text(table + "\n")
    with (out / "compare.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summaries[0]))
        writer.writeheader()
        writer.writerows(summaries)
    chart = chart_png(summaries, out / "compare.png", episodes)
    return table, (out / "compare.md", out / "compare.csv", chart)


def chart_png(summaries: Sequence[dict[str, Any]], path: Path, episodes: int) -> Path:
    """Success (with 95 % whiskers) and grasp quality, one bar per kind of agent
    (scripted, each learned algorithm, random, still) in each task; where one kind has
    several agents on a task, the best by success is shown."""
    tasks = sorted({s["env_id"] for s in summaries})
    kinds = list(dict.fromkeys(s["kind"] for s in summaries))
    best: dict[tuple[str, str], dict[str, Any]] = {}
    for s in summaries:
        key = (s["kind"], s["env_id"])
        if key not in best or s["success_rate"] > best[key]["success_rate"]:
            best[key] = s

    def values(name: str) -> dict[str, list[float]]:
        return {k: [best[k, t][name] if (k, t) in best else np.nan for t in tasks] for k in kinds}

    errors = {
        k: [
            (best[k, t]["success_ci_low"], best[k, t]["success_ci_high"])
            if (k, t) in best
            else (0, 0)
            for t in tasks
        ]
        for k in kinds
    }
    labels = [t.split("/")[-1].removesuffix("-v0") for t in tasks]
    quality = values("mean_quality")
    top = max([v for vs in quality.values() for v in vs if np.isfinite(v)] + [1e-6])
    success_img = bar_chart(
        labels,
        values("success_rate"),
        None,
        f"Success over {episodes} seeded episodes (95 % CI)",
        "success rate",
        (0.0, 1.0),
        errors,
    )
    quality_img = bar_chart(
        labels,
        quality,
        None,
        "Grasp quality: mean Ferrari-Canny epsilon per step",
        "epsilon",
        (0.0, 1.15 * top),
        size=(success_img.shape[1], success_img.shape[0]),
    )
    return write_png(np.vstack([success_img, quality_img]), path)
