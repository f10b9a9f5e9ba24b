"""Benchmark jobs in this process or in a pool of processes."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import TypeVar

__all__ = ["collect_jobs", "run_jobs"]

J = TypeVar("J")
R = TypeVar("R")


def run_jobs(
    work: Callable[[J], R],
    jobs: Iterable[J],
    workers: int,
    each: Callable[[R], None],
    chunksize: int = 1,
) -> None:
    """``work`` on every job, in this process (``workers`` 1) or in a pool of
    ``workers`` processes; ``each`` gets every result as it comes, in job order.

    Raises:
        ValueError: ``workers`` is below 1.
    """
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if workers == 1:
        for job in jobs:
            each(work(job))
        return
    with ProcessPoolExecutor(workers) as pool:
        for result in pool.map(work, jobs, chunksize=chunksize):
            each(result)


def collect_jobs(
    work: Callable[[J], R],
    jobs: Sequence[J],
    workers: int,
    progress: Callable[[str], None] | None,
    describe: Callable[[R], str],
) -> list[R]:
    """:func:`run_jobs`, the results in a list; ``progress`` (if given) gets a line
    ``[done/total] describe(result)`` as each result comes."""
    results: list[R] = []

    def note(result: R) -> None:
        results.append(result)
        if progress is not None:
            progress(f"[{len(results)}/{len(jobs)}] {describe(result)}")

    run_jobs(work, jobs, workers, note)
    return results
