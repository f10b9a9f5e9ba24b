"""The compiled hot path: numba's machine code is cached on disk and reused by the
next process (graspenv/jit.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

_CALL = """
import json, numpy as np
from graspenv.geometry import footprint_depths
footprint_depths(np.zeros((3, 2)), np.array([1]), np.array([[0.01, 0.0, 0.0]]),
                 np.zeros((1, 3)), np.eye(3).reshape(1, 9))
stats = footprint_depths.stats
print(json.dumps({"hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values())}))
"""


def _run(cache: Path) -> dict[str, int]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run(
        [sys.executable, "-c", _CALL], env=env, capture_output=True, text=True, check=True,
        timeout=300,
    )  # fmt: skip
    result: dict[str, int] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def test_kernels_compile_once_and_load_from_the_cache_in_the_next_process(
    tmp_path: Path,
) -> None:
    first = _run(tmp_path)
    assert first == {"hits": 0, "misses": 1}  # compiled and written
    assert any(tmp_path.rglob("*.nbi"))
    second = _run(tmp_path)
    assert second == {"hits": 1, "misses": 0}  # loaded, not compiled
