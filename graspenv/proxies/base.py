"""What every proxy method shares: the per-frame command it hands the physics."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from graspenv.contacts.tracking import ContactFrame
from graspenv.jit import njit

__all__ = ["ProxyCommand", "ProxyMethod", "rigid_rotation", "rotation_kernel"]


@dataclass(frozen=True)
class ProxyCommand:
    """Where the proxies of one frame must go.

    Attributes:
        particles: pool ids, shape (K, L): K contour points, L particles stacked on
            each (column 0 at the bottom).
        targets: each point's position at the end of the frame, metres, world frame,
            shape (K, 2).
        spin: rotation rate about +z of the contour each point belongs to, rad/s,
            shape (K,).
        bodies: for the rigid method, one handle per contact, shape (B,).
        body_targets: (x, y, yaw) of each rigid body at the end of the frame, metres
            and radians, world frame, shape (B, 3).
        culled: contour points left without a particle this frame because they
            cannot touch an object soon (``proxy.cull``); they are not in
            ``particles``.
        born: which rows of ``particles`` were put down this frame, shape (K,)
            (persistent method; empty for the others). A pool id can be given back
            by one point and handed to another in the same frame, so only rows not
            born continue their point of the last frame.
    """

    particles: NDArray[np.int64]
    targets: NDArray[np.float64]
    spin: NDArray[np.float64]
    bodies: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    body_targets: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    culled: int = 0
    born: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def n_particles(self) -> int:
        return int(self.particles.size)


class ProxyMethod(Protocol):
    """Turns tracked contacts into proxy targets, keeping its own bookkeeping."""

    def update(self, frame: ContactFrame, mask: NDArray[np.uint8]) -> ProxyCommand:
        """Bookkeeping for one camera frame; returns where the proxies must go."""
        ...

    def reset(self) -> None:
        """Forget every contact (the physics pool is reset by the world)."""
        ...


def rigid_rotation(before: NDArray[np.float64], after: NDArray[np.float64]) -> float:
    """The rotation angle of the best rigid motion taking points ``before`` to ``after``.

    Least squares (2-D Kabsch): with both point sets centred, the angle is
    ``atan2(Σ a × b, Σ a · b)``.

    Args:
        before: metres, world frame, shape (N, 2).
        after: the same points later, shape (N, 2).

    Returns:
        radians, counter-clockwise; 0 for fewer than two points.
    """
    before = np.ascontiguousarray(before, dtype=np.float64)
    after = np.ascontiguousarray(after, dtype=np.float64)
    if before.shape != after.shape or before.ndim != 2 or before.shape[1] != 2:
        raise ValueError(
            f"before and after must both have shape (N, 2), got {before.shape} and {after.shape}"
        )
    return rotation_kernel(before, after)


@njit
def rotation_kernel(before: NDArray[np.float64], after: NDArray[np.float64]) -> float:
    """:func:`rigid_rotation`, compiled, for checked (N, 2) arrays (the per-frame hand
    turn): sums in point order."""
    n = len(before)
    if n < 2:
        return 0.0
    bx, by, ax, ay = 0.0, 0.0, 0.0, 0.0
    for i in range(n):
        bx += before[i, 0]
        by += before[i, 1]
        ax += after[i, 0]
        ay += after[i, 1]
    bx, by, ax, ay = bx / n, by / n, ax / n, ay / n
    cross, dot = 0.0, 0.0
    for i in range(n):
        px, py = before[i, 0] - bx, before[i, 1] - by
        qx, qy = after[i, 0] - ax, after[i, 1] - ay
        cross += px * qy - py * qx
        dot += px * qx + py * qy
    if cross == 0.0 and dot == 0.0:
        return 0.0
    return float(np.arctan2(cross, dot))
