"""Evaluations as Ray tasks: ``graspenv compare --ray`` and ``graspenv eval --ray``.

The episodes of every (environment, agent) pair are cut into batches of seeds; each
batch is one Ray task (:func:`graspenv.cluster.run_tasks`) that loads the agent and
builds the environment inside its worker. Each episode's result follows from its
own seed alone (the environment is rebuilt at every reset, and an agent that draws
at random is seeded per episode, :meth:`Agent.seed`), so the batches, put back in
seed order, give the same evaluation as one process playing every seed in turn:
the table is the same figure for figure, whichever worker or node ran which batch.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from graspenv import cluster

from .evaluate import Episode, Evaluation, evaluate
from .loading import load_agent

__all__ = ["BATCH", "evaluate_batch", "evaluations"]

#: Episodes per Ray task: small enough to spread 100 episodes of one pair over many
#: workers, large enough that building the environment is a small share of a task.
BATCH = 10


def evaluate_batch(
    env_id: str, spec: str, seeds: Sequence[int], config: str | None = None
) -> tuple[tuple[Episode, ...], str]:
    """One task: the episodes of ``seeds``, and the node that played them."""
    episodes = evaluate(env_id, load_agent(spec, seeds[0]), seeds, config).episodes
    return episodes, cluster.node()


def evaluations(
    jobs: Sequence[tuple[str, str]],
    seeds: Sequence[int],
    config: str | Path | None = None,
    address: str | None = None,
    batch: int = BATCH,
    progress: Callable[[int, int], None] | None = None,
    num_cpus: int | None = None,
) -> tuple[dict[tuple[str, str], Evaluation], set[str]]:
    """Every (environment id, agent spec) job over ``seeds`` on Ray (a local instance
    with ``num_cpus``, default every core, or the cluster at ``address``). Returns the
    evaluations, keyed by job, and the nodes that ran them."""
    if batch < 1:
        raise ValueError(f"batch must be at least 1, got {batch}")
    cluster.connect(address, num_cpus)
    seeds = list(seeds)
    chunks = [seeds[i : i + batch] for i in range(0, len(seeds), batch)]
    calls = [
        (env_id, spec, chunk, None if config is None else str(config))
        for env_id, spec in jobs
        for chunk in chunks
    ]
    results = cluster.run_tasks(evaluate_batch, calls, "episode batches", progress)
    out: dict[tuple[str, str], Evaluation] = {}
    for j, (env_id, spec) in enumerate(jobs):
        agent = load_agent(spec)
        parts = results[j * len(chunks) : (j + 1) * len(chunks)]
        episodes = tuple(e for part, _ in parts for e in part)
        out[env_id, spec] = Evaluation(env_id, agent.label, agent.kind, episodes)
    return out, {where for _, where in results}
