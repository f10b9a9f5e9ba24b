"""Slip and the Coulomb limit: how an object moves against the fingers that grip it
(numpy only).

Frames and units: world frame (origin at the table centre, z up), SI units (m, m/s,
N); only the table-plane components of positions and velocities enter.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["coulomb_slip_force", "planar_slip", "rigid_velocity_at"]


def rigid_velocity_at(
    points: ArrayLike, velocities: ArrayLike, query: ArrayLike
) -> NDArray[np.float64]:
    """Velocity at ``query`` of the planar rigid motion that best fits moving points.

    Fits a twist (v, ω), ``u_i ≈ v + ω ẑ × (p_i − p̄)``, by least squares (p̄ the
    centroid, where the fit decouples: v is the mean velocity and ω the
    moment-weighted mean rotation rate). With one point, or all points at one place,
    ω = 0 (pure translation).

    Args:
        points: points, metres, world frame, shape (P, 2), P >= 1.
        velocities: their velocities, m/s, world frame, shape (P, 2).
        query: where to evaluate the fitted motion, metres, shape (2,).

    Returns:
        The fitted rigid velocity at ``query``, m/s, shape (2,).
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    u = np.asarray(velocities, dtype=float).reshape(-1, 2)
    q = np.asarray(query, dtype=float)
    if len(p) == 0 or u.shape != p.shape:
        raise ValueError(
            f"points and velocities must both have shape (P, 2), P >= 1, got {p.shape}"
            f" and {u.shape}"
        )
    centroid = p.mean(axis=0)
    mean_velocity = u.mean(axis=0)
    r = p - centroid
    du = u - mean_velocity
    moment = float(np.sum(r * r))
    # Below this the points are one point to rounding: no rotation is observable.
    if moment <= 1e-24 * max(1.0, float(np.max(np.abs(p)))) ** 2:
        omega = 0.0
    else:
        omega = float(np.sum(r[:, 0] * du[:, 1] - r[:, 1] * du[:, 0])) / moment
    d = q - centroid
    return mean_velocity + omega * np.array([-d[1], d[0]])


def planar_slip(
    object_position: ArrayLike,
    object_velocity: ArrayLike,
    finger_points: ArrayLike,
    finger_velocities: ArrayLike,
) -> float:
    """Speed of an object relative to the rigid motion of the fingers touching it.

    Args:
        object_position: the object's centre, metres, world frame, shape (2,) or (3,)
            (z ignored).
        object_velocity: its linear velocity, m/s, world frame, shape (2,) or (3,)
            (z ignored).
        finger_points: where the fingers (particles) touch it, metres, shape (P, 2)
            or (P, 3); P may be 0.
        finger_velocities: the fingers' velocities there, m/s, shape (P, 2) or (P, 3).

    Returns:
        ``|v_object − v_fit(centre)|`` in the table plane, m/s, with v_fit from
        :func:`rigid_velocity_at`; the object's planar speed when P = 0.
    """
    centre = np.asarray(object_position, dtype=float)[:2]
    velocity = np.asarray(object_velocity, dtype=float)[:2]
    points = np.asarray(finger_points, dtype=float)
    if points.size == 0:
        return float(np.linalg.norm(velocity))
    fingers = np.asarray(finger_velocities, dtype=float)
    fit = rigid_velocity_at(points[:, :2], fingers[:, :2], centre)
    return float(np.linalg.norm(velocity - fit))


def coulomb_slip_force(grip_force: float, mu: float) -> float:
    """Tangential force at which a two-sided squeeze lets the object slip (Coulomb).

    Convention: two opposing fingers each press on the object with the normal force
    ``grip_force`` (N per side); each can hold at most ``μ N`` of tangential force,
    so the object slips beyond ``2 μ N``. :attr:`GraspMetrics.grip_force` sums both
    sides, so for a symmetric squeeze pass half of it.

    Args:
        grip_force: normal force of each finger, newtons, >= 0.
        mu: friction coefficient between finger and object, >= 0.

    Returns:
        The slip threshold, newtons.
    """
    if not grip_force >= 0.0 or not mu >= 0.0:
        raise ValueError(f"grip_force and mu must be >= 0, got {grip_force} and {mu}")
    return 2.0 * mu * grip_force
