"""The plain-numpy forms of the proxies' compiled kernels, as they stood before
they were compiled: the oracles the kernels are checked against on random inputs
(tests/proxies/test_side_load.py). Not used by the package; each function takes the
arguments of the function it checks (the frame's step as one tuple) and the
constants of its module, and gives its result."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def shared_side_load(
    reach: NDArray[np.float64],
    outward: NDArray[np.float64],
    group: NDArray[np.int64],
    friction: NDArray[np.float64],
    wrapped: float,
) -> NDArray[np.float64]:
    """:func:`graspenv.proxies.side_hold.shared_side_load` with whole-array numpy
    operations: the groups numbered by ``np.unique``, their sums by ``np.bincount``
    and ``np.add.at``."""
    tangent = np.column_stack([-outward[:, 1], outward[:, 0]])
    along = np.einsum("ij,ij->i", reach, tangent)
    deep = -np.einsum("ij,ij->i", reach, outward)
    shift = np.zeros_like(reach)
    press = np.flatnonzero(deep > 0.0)
    # A particle further from its place in the contact (its offset less its group's
    # mean) than its own friction holds is not stuck with the rest: it slides back
    # towards its point as before (else particles could drift along a held side,
    # ever further from their points, and bunch).
    _, group = np.unique(group[press], return_inverse=True)
    mean = np.bincount(group, along[press]) / np.bincount(group)
    stuck = np.abs(along[press] - mean[group]) <= friction[press] * deep[press]
    press, group = press[stuck], group[stuck]
    if press.size == 0:
        return shift
    along, deep, friction = along[press], deep[press], friction[press]
    count = np.bincount(group)
    normal = np.zeros((count.size, 2))
    np.add.at(normal, group, outward[press])
    load = np.bincount(group, along)
    depth = np.bincount(group, deep)
    limit = np.bincount(group, friction * deep)
    shared = (np.hypot(normal[:, 0], normal[:, 1]) >= wrapped * count) & (np.abs(load) < limit)
    share = np.where(shared[group], deep * load[group] / depth[group] - along, 0.0)
    shift[press] = share[:, None] * tangent[press]
    return shift


def shared_rows(frame: tuple[NDArray[Any], ...], wrapped: float) -> NDArray[np.float64]:
    """The body of :func:`graspenv.proxies.side_hold.shared_targets` with numpy's
    fancy indexing: the pressing rows with a side normal gathered, their load shared
    (:func:`shared_side_load`), the shifts added to a copy of ``targets``. ``frame``
    holds the compiled form's arguments (``_shared_rows`` in that module), in order."""
    targets, rows, at, normal, pressed, track_of, owner, friction = frame
    keep = pressed & np.any(normal != 0.0, axis=1)
    rows, body = rows[keep], owner[rows[keep]]
    targets = targets.copy()
    targets[rows] += shared_side_load(
        targets[rows] - at[keep, :2],
        normal[keep],
        track_of[rows] * len(friction) + body,
        friction[body],
        wrapped,
    )
    return targets
