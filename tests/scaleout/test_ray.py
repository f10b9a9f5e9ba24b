"""Scale-out on Ray (``tests/scaleout/suite.py``), in a network namespace with only
loopback: Ray binds its servers to the machine's address, and inside the namespace
loopback is the only one, so nothing listens beyond it and nothing is reached.

Needs root (``unshare --net``) and the ``ray`` extra, which ``make test`` installs;
skipped with the reason where either is missing, except in CI, where it fails.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from graspenv import cluster

SUITE = Path(__file__).with_name("suite.py")
ROOT = Path(__file__).resolve().parents[2]


def _missing() -> str | None:
    if importlib.util.find_spec("ray") is None:
        return "Ray is not installed (the ray extra: make test installs it)"
    if os.geteuid() != 0 or not shutil.which("unshare") or not shutil.which("ip"):
        return "a loopback-only network namespace needs root, unshare and ip"
    return None


def test_the_ray_suite_in_a_loopback_only_network() -> None:
    reason = _missing()
    if reason is not None:
        if os.environ.get("CI"):
            pytest.fail(f"CI must run the Ray suite: {reason}")
        pytest.skip(reason)
    command = f"ip link set lo up && exec {sys.executable} -m pytest -q -p no:cacheprovider {SUITE}"
    run = subprocess.run(
        ["unshare", "--net", "--", "sh", "-c", command],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=480,
    )
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-3000:]
    assert " passed" in run.stdout and "skipped" not in run.stdout, run.stdout[-2000:]


def test_an_unreachable_cluster_is_a_clear_error_at_once() -> None:
    with pytest.raises(ValueError, match=re.escape("cannot reach the Ray cluster at 127.0.0.1:1")):
        cluster._reachable("127.0.0.1:1", timeout=2.0)
    with pytest.raises(ValueError, match="HOST:PORT"):
        cluster._reachable("no-port-here")
