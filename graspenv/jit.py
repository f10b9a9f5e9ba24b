"""The compiled hot path: numba's ``njit`` with the project's settings.

Per-frame work on contours, particles, masks and contacts runs in a few compiled
functions per frame (``docs/design.md``, section 3, "The lean frame"); Python keeps the
orchestration and every PyBullet call. Each compiled function sits in the module of
the stage that owns it; the plain-numpy forms they replaced are kept as test oracles
in ``tests/contacts/reference.py``. Compiled functions do not check their indices:
the public functions that call them check their arguments first.

Settings, and why:

- ``cache=True``: the machine code is written to disk on the first call (beside the
  module in ``__pycache__``, or in numba's per-user cache where that folder is
  read-only) and loaded by every later process, so only the first run on a machine
  pays the compile (``graspenv bench --speed`` reports it).
- no ``fastmath``: IEEE arithmetic in the order written, so runs stay bit-identical
  from process to process and machine code to machine code.
- ``error_model="numpy"``: a division by zero gives inf or NaN as in numpy instead
  of raising, which also keeps the checks out of the inner loops.

``NUMBA_DISABLE_JIT=1`` runs every kernel as plain Python (slowly), for debugging.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba

__all__ = ["njit"]

F = TypeVar("F", bound=Callable[..., Any])


def njit(function: F) -> F:
    """Compile ``function`` with numba in nopython mode, cached on disk (see above)."""
    return cast(F, numba.njit(cache=True, nogil=True, error_model="numpy")(function))
