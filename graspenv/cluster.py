"""Scale-out on Ray: the benchmarks' and evaluations' work as Ray tasks.

Ray (``pip install 'graspenv[ray]'``) runs the tasks on this machine's cores, or on
an existing cluster (``ray start --head`` on one machine, ``ray start --address
HEAD:6379`` on the others, graspenv installed on all). Each task builds its own
environments and PyBullet clients inside the worker: nothing holding a physics
client crosses a process. A task whose worker dies is retried (:data:`MAX_RETRIES`),
so a killed worker delays the table but does not change it.

A local instance binds to loopback only, with the dashboard and usage statistics
off.
"""

from __future__ import annotations

import os
import socket
import sys
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["MAX_RETRIES", "connect", "node", "run_tasks"]

#: Times Ray runs a task again when its worker process dies.
MAX_RETRIES = 3


def _reachable(address: str, timeout: float = 5.0) -> None:
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"a Ray address is HOST:PORT (e.g. 10.0.0.5:6379), got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except OSError as err:
        raise ValueError(f"cannot reach the Ray cluster at {address}: {err}") from err


def connect(address: str | None = None, num_cpus: int | None = None) -> dict[str, Any]:
    """Join the cluster at ``address`` (``HOST:PORT``, or ``"auto"`` for the one this
    machine belongs to), or start a local instance with ``num_cpus`` (default: this
    machine's cores). A session already connected is kept. Returns the cluster's
    resources.

    Raises:
        ValueError: the address is malformed or cannot be reached (checked with a
            plain TCP connection first: Ray itself would keep retrying for minutes).
        ModuleNotFoundError: Ray is not installed (the ``ray`` extra).
    """
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    import ray

    if not ray.is_initialized():
        if address is None:
            # "local": a new instance even where another run left one on this
            # machine (joining it would fail on num_cpus, or share its cores).
            ray.init(
                address="local",
                num_cpus=num_cpus,
                include_dashboard=False,
                _node_ip_address="127.0.0.1",
                log_to_driver=False,
                configure_logging=False,
            )
        else:
            if address != "auto":
                _reachable(address)
            ray.init(address=address, log_to_driver=False, configure_logging=False)
    resources: dict[str, Any] = ray.cluster_resources()
    return resources


def node() -> str:
    """The Ray node this runs on (its id, shortened) and the machine's name."""
    import ray

    return f"{socket.gethostname()}/{ray.get_runtime_context().get_node_id()[:8]}"


def run_tasks(
    function: Callable[..., Any],
    calls: Sequence[tuple[Any, ...]],
    label: str = "tasks",
    progress: Callable[[int, int], None] | None = None,
) -> list[Any]:
    """``function(*call)`` for every call, as Ray tasks of one CPU each; the results
    in the order of ``calls``, whichever worker ran each. A progress bar on stderr
    covers the whole cluster's work (or ``progress(done, total)`` is called).

    ``function`` must be importable by the workers (a module-level function of an
    installed package) and each call's arguments picklable.
    """
    import ray

    remote = ray.remote(num_cpus=1, max_retries=MAX_RETRIES)(function)
    refs = [remote.remote(*call) for call in calls]
    where = {ref: i for i, ref in enumerate(refs)}
    results: list[Any] = [None] * len(refs)
    pending = list(refs)
    bar = None
    if progress is None:
        from tqdm import tqdm

        bar = tqdm(total=len(refs), desc=label, file=sys.stderr, unit="task")
    try:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            for ref in ready:
                results[where[ref]] = ray.get(ref)
            done = len(refs) - len(pending)
            if bar is not None:
                bar.update(len(ready))
            elif progress is not None:
                progress(done, len(refs))
    finally:
        if bar is not None:
            bar.close()
    return results
