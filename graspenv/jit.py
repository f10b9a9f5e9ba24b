"""The compiled hot path: numba's ``njit`` with the project's settings.

Per-frame work on contours, particles, masks and contacts runs in a few compiled
functions per frame (``docs/design.md``, section 3, "The lean frame"); Python keeps the
orchestration and every PyBullet call. Each compiled function sits in the module of
the stage that owns it; the plain-numpy forms they replaced are kept as test oracles
in ``tests/contacts/reference.py`` and ``tests/proxies/reference.py``. Compiled
functions do not check their indices: the public functions that call them check
their arguments first, or take them from the frame's own steps before them.

Settings, and why:

- ``cache=True``: the machine code is written to disk on the first call and loaded
  by every later process, so only the first run on a machine pays the compile
  (``graspenv bench --speed`` reports it). The cache lives in a folder named by a
  hash of every source file of the package (:func:`cache_folder`): numba checks
  only the calling function's own file, and machine code compiled into a caller
  keeps the callees it was compiled with, so a kernel changed in one module ran
  its old code from another module's cache (measured: a changed landing rule in
  ``graspenv/contacts/resample.py`` left the bench's noisy turn at its old 4.46°
  until ``graspenv/proxies/persistent.py`` changed too; 2.03° once it ran). Any
  change to the package now compiles everything once. Each source tree's folder
  stays behind it (about 6 MB; this project's own checkout had kept ten), so when a
  process makes a new one it removes the other trees' folders that nothing has
  written to for :data:`STALE_DAYS` days (:func:`prune_stale`).
- no ``fastmath``: IEEE arithmetic in the order written, so runs stay bit-identical
  from process to process and machine code to machine code.
- ``error_model="numpy"``: a division by zero gives inf or NaN as in numpy instead
  of raising, which also keeps the checks out of the inner loops.

``NUMBA_DISABLE_JIT=1`` runs every kernel as plain Python (slowly), for debugging.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba

__all__ = ["STALE_DAYS", "cache_folder", "njit", "prune_stale", "sources_key"]

F = TypeVar("F", bound=Callable[..., Any])

_PACKAGE = Path(__file__).resolve().parent


def sources_key(root: Path = _PACKAGE) -> str:
    """A hash of every ``.py`` file under ``root`` (names and contents), 16 hex
    digits: it changes whenever any source does."""
    digest = hashlib.blake2b(digest_size=8)
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def cache_folder(root: Path = _PACKAGE) -> Path:
    """Where the compiled kernels are cached: ``graspenv-<sources_key>`` in
    ``NUMBA_CACHE_DIR`` if set, else in the package's ``__pycache__/numba`` (or,
    where the package is read-only, ``~/.cache/graspenv/numba``)."""
    chosen = os.environ.get("NUMBA_CACHE_DIR")
    if chosen:
        base = Path(chosen)
    elif os.access(root, os.W_OK):
        base = root / "__pycache__" / "numba"
    else:
        home = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        base = Path(home) / "graspenv" / "numba"
    return base / f"graspenv-{sources_key(root)}"


#: Days without a write after which another source tree's cache folder is removed.
STALE_DAYS = 7.0


def prune_stale(folder: Path, days: float = STALE_DAYS) -> list[Path]:
    """Remove the ``graspenv-*`` folders beside ``folder`` (other source trees'
    caches) whose newest file is older than ``days`` days; ``folder`` itself is
    kept. A cache is only ever compiled again, so nothing is lost; one that another
    process still uses is written afresh if that process compiles again.

    Returns:
        The folders removed.
    """
    if not folder.parent.is_dir():
        return []
    cutoff = time.time() - days * 86400.0
    removed = []
    for other in sorted(folder.parent.glob("graspenv-*")):
        if other != folder and other.is_dir() and _newest_write(other) < cutoff:
            shutil.rmtree(other, ignore_errors=True)
            removed.append(other)
    return removed


def _newest_write(folder: Path) -> float:
    """The latest modification time of ``folder`` or anything in it; a file that
    vanishes while it is read (another process pruning, or a dangling link) does not
    count, so that importing the package never fails on another tree's cache."""
    newest = 0.0
    for path in [folder, *folder.rglob("*")]:
        try:
            newest = max(newest, path.stat().st_mtime)
        except OSError:
            continue
    return newest


_FOLDER = cache_folder()
if not _FOLDER.exists():  # a new source tree: the moment old ones are left behind
    prune_stale(_FOLDER)
# Read by numba when each cached function is decorated, so set before any is.
numba.config.CACHE_DIR = str(_FOLDER)  # type: ignore[attr-defined]


def njit(function: F) -> F:
    """Compile ``function`` with numba in nopython mode, cached on disk (see above)."""
    return cast(F, numba.njit(cache=True, nogil=True, error_model="numpy")(function))
