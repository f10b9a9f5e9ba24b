"""Benchmark jobs in this process or in a pool of processes."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
from typing import TypeVar

__all__ = ["run_jobs"]

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
