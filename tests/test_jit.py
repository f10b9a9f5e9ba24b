"""The compiled hot path: numba's machine code is cached on disk and reused by the
next process (graspenv/jit.py)."""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

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


# numba compiles these only with SciPy's BLAS and LAPACK, which graspenv does not
# depend on: a kernel using one works where SciPy happens to be installed (the dev
# tools bring it) and fails everywhere else.
_NEEDS_SCIPY = {"dot", "vdot", "cross", "matmul", "inner", "outer", "linalg", "einsum"}


def _compiled_functions() -> list[tuple[str, ast.FunctionDef]]:
    found = []
    for path in sorted(Path("graspenv").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and any(
                isinstance(d, ast.Name) and d.id == "njit" for d in node.decorator_list
            ):
                found.append((f"{path}:{node.name}", node))
    return found


def test_compiled_kernels_need_no_scipy() -> None:
    kernels = _compiled_functions()
    assert len(kernels) > 20  # the scan finds them
    for where, node in kernels:
        for inner in ast.walk(node):
            if isinstance(inner, ast.BinOp):
                assert not isinstance(inner.op, ast.MatMult), f"{where} uses @"
            if (
                isinstance(inner, ast.Attribute)
                and isinstance(inner.value, ast.Name)
                and inner.value.id == "np"
            ):
                assert inner.attr not in _NEEDS_SCIPY, f"{where} uses np.{inner.attr}"


def test_the_cache_folder_changes_with_any_source(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # numba checks only a cached function's own file; machine code compiled into a
    # caller keeps the callees it was compiled with. The folder is named by every
    # source, so a change anywhere starts a fresh cache.
    from graspenv.jit import cache_folder, sources_key

    package = tmp_path / "package"
    (package / "sub").mkdir(parents=True)
    (package / "a.py").write_text("x = 1\n")
    (package / "sub" / "b.py").write_text("y = 2\n")
    before = sources_key(package)
    assert sources_key(package) == before
    (package / "sub" / "b.py").write_text("y = 3\n")
    assert sources_key(package) != before
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    assert cache_folder(package) == tmp_path / "cache" / f"graspenv-{sources_key(package)}"


def test_other_source_trees_caches_untouched_for_a_week_are_removed(tmp_path: Path) -> None:
    import os
    import time

    from graspenv.jit import STALE_DAYS, prune_stale

    now = time.time()
    current = tmp_path / "graspenv-current"
    stale = tmp_path / "graspenv-stale"
    recent = tmp_path / "graspenv-recent"  # an old folder with a file written today
    other = tmp_path / "someone-else"
    for folder in (current, stale, recent, other):
        (folder / "kernels").mkdir(parents=True)
        (folder / "kernels" / "k.nbi").write_bytes(b"x")
    # A file gone while the folder is read (another process pruning it): as a
    # dangling link, whose stat fails as a vanished file's does.
    (stale / "kernels" / "gone.nbi").symlink_to(stale / "nowhere")
    old = now - (STALE_DAYS + 1) * 86400
    for folder in (current, stale, recent, other):
        for path in (folder / "kernels" / "k.nbi", folder / "kernels", folder):
            os.utime(path, (old, old))
    os.utime(recent / "kernels" / "k.nbi", (now, now))
    assert prune_stale(current) == [stale]
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "graspenv-current",
        "graspenv-recent",
        "someone-else",
    ]
    assert prune_stale(tmp_path / "missing" / "graspenv-x") == []
