"""Grasp-stability metrics from the contacts on an object (numpy only).

Everything here works on plain arrays: :func:`grasp_metrics` reads any object with the
attribute names of :class:`graspenv.physics.ContactReport` (see
:class:`ContactArrays`), so this module never imports PyBullet.

Frames and units: world frame (origin at the table centre, z up), SI units (m, m/s,
N, rad); quaternions are (x, y, z, w). Grasp quality is planar: the table is the
plane of the grasp, so only the in-plane components of contact positions, normals and
velocities enter :func:`ferrari_canny` and the slip.

The pieces live by responsibility and are re-exported here: the Ferrari–Canny
epsilon and force closure in :mod:`graspenv.tasks.quality`, slip and the Coulomb
limit in :mod:`graspenv.tasks.slip`; this module gathers them into
:class:`GraspMetrics` for one object's contact report.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.geometry import tilt_angle
from graspenv.jit import njit
from graspenv.tasks.quality import ferrari_canny
from graspenv.tasks.slip import coulomb_slip_force, planar_slip, rigid_velocity_at

__all__ = [
    "ContactArrays",
    "GraspMetrics",
    "coulomb_slip_force",
    "ferrari_canny",
    "grasp_metrics",
    "planar_slip",
    "rigid_velocity_at",
    "tilt_angle",
]


class ContactArrays(Protocol):
    """The per-contact arrays :func:`grasp_metrics` reads from a contact report.

    :class:`graspenv.physics.ContactReport` has them; any object with these
    attributes does. One row per contact point of one object, K rows.
    """

    @property
    def particle(self) -> NDArray[np.int64]:
        """Id of the particle in each contact, -1 when not a particle, shape (K,)."""
        ...

    @property
    def position(self) -> NDArray[np.float64]:
        """Contact points on the object, metres, world frame, shape (K, 3)."""
        ...

    @property
    def normal(self) -> NDArray[np.float64]:
        """Unit contact normals pointing into the object, world frame, shape (K, 3)."""
        ...

    @property
    def normal_force(self) -> NDArray[np.float64]:
        """Normal force on the object, newtons, >= 0, shape (K,)."""
        ...

    @property
    def distance(self) -> NDArray[np.float64]:
        """Signed separation, metres (negative: penetration), shape (K,)."""
        ...


class _Touches(NamedTuple):
    """The rows of a contact report where a particle touches the object, as
    :func:`_merge_contacts` reads them: K rows.

    Attributes:
        particle: the particle's id, shape (K,).
        position: the contact point, metres, world frame, (K, 3).
        normal: the unit normal into the object, (K, 3).
        normal_force: newtons, (K,).
        velocity: the particle's planar velocity, m/s, (K, 2).
    """

    particle: NDArray[np.int64]
    position: NDArray[np.float64]
    normal: NDArray[np.float64]
    normal_force: NDArray[np.float64]
    velocity: NDArray[np.float64]


@dataclass(frozen=True)
class GraspMetrics:
    """How well an object is held, from one physics step.

    Attributes:
        grip_force: sum of the normal forces of all particle contacts on the object,
            newtons (both sides of a squeeze, and particles pressing from above).
        n_contacts: number of distinct particles touching the object.
        force_closure: whether the particles' side contacts hold the object in force
            closure in the table plane (``epsilon > 0``).
        epsilon: planar Ferrari–Canny quality of those contacts, dimensionless
            (force per unit total normal force), >= 0; see :func:`ferrari_canny`.
        slip: speed of the object's centre relative to the best-fit rigid planar
            motion of the touching particles, m/s; the object's planar speed when no
            particle touches it.
        tilt: angle between the object's z axis and the world's, radians in [0, π].
        penetration: deepest particle penetration into the object, metres, >= 0.
    """

    grip_force: float
    n_contacts: int
    force_closure: bool
    epsilon: float
    slip: float
    tilt: float
    penetration: float

    @classmethod
    def empty(cls) -> GraspMetrics:
        """Metrics of an object at rest that nothing touches (all zero, no closure)."""
        return cls(
            grip_force=0.0,
            n_contacts=0,
            force_closure=False,
            epsilon=0.0,
            slip=0.0,
            tilt=0.0,
            penetration=0.0,
        )


def grasp_metrics(
    report: ContactArrays,
    object_position: ArrayLike,
    object_quaternion: ArrayLike,
    object_linear_velocity: ArrayLike,
    object_angular_velocity: ArrayLike,
    particle_velocities: ArrayLike,
    mu: float,
    *,
    min_horizontal_normal: float = 0.5,
) -> GraspMetrics:
    """Grip force, force closure, slip, tilt and penetration of one object.

    Only particle contacts (``report.particle >= 0``) count: table and object
    contacts are ignored. A particle *touches* the object when one of its rows has
    ``distance <= 0`` or a positive normal force (Bullet also reports points a
    little apart, with no force). A particle may touch with several points (a disc or
    a stack of spheres): they are merged into one contact per particle, at the
    normal-force-weighted mean point with the normalised force-weighted mean normal
    (plain means if its force is 0). That keeps the wrench set small without
    changing what the particle can push, and weighs every particle once in the slip.

    For the grasp quality, a merged contact is a side contact when the horizontal
    part of its normal has length >= ``min_horizontal_normal``; particles pressing
    from above have no planar friction cone and are left out. Torques are about the
    object's position (its centre of mass).

    Args:
        report: the object's contacts (e.g. ``PhysicsWorld.contact_report(name)``).
        object_position: the object's centre, metres, world frame, shape (3,).
        object_quaternion: its orientation (x, y, z, w), world frame, shape (4,).
        object_linear_velocity: m/s, world frame, shape (3,); the planar part sets
            the slip.
        object_angular_velocity: rad/s, world frame, shape (3,); unused (the slip is
            measured at the centre), taken so the call mirrors
            ``Simulation.object_velocity``.
        particle_velocities: linear velocity of the particle in each particle row of
            ``report`` (rows with ``particle >= 0``, in order), m/s, world frame,
            shape (Kp, 2) or (Kp, 3) (z ignored); one row per report row, (K, 2|3),
            is accepted too.
        mu: particle–object friction coefficient (Bullet combines the two bodies'
            coefficients as their product), >= 0.
        min_horizontal_normal: side-contact threshold on the horizontal length of the
            unit normal, in [0, 1] (0.5: at most 60° from the table plane).

    Returns:
        The metrics; see :class:`GraspMetrics`.

    Raises:
        ValueError: on mismatched shapes, or an invalid ``mu``.
    """
    del object_angular_velocity  # part of the object's state, not of this measure
    particle = np.asarray(report.particle, dtype=np.int64).reshape(-1)
    position = np.asarray(report.position, dtype=float).reshape(-1, 3)
    normal = np.asarray(report.normal, dtype=float).reshape(-1, 3)
    normal_force = np.asarray(report.normal_force, dtype=float).reshape(-1)
    distance = np.asarray(report.distance, dtype=float).reshape(-1)
    centre = np.asarray(object_position, dtype=float).reshape(-1)[:2]
    planar_velocity = np.asarray(object_linear_velocity, dtype=float).reshape(-1)[:2]
    is_particle = particle >= 0
    velocity_rows = _velocity_rows(particle_velocities, is_particle)

    grip_force = float(np.sum(normal_force[is_particle]))
    penetration = max(0.0, -float(np.min(distance[is_particle], initial=0.0)))
    tilt = tilt_angle(np.asarray(object_quaternion, dtype=float))

    touching = is_particle & ((distance <= 0.0) | (normal_force > 0.0))
    if not touching.any():
        return GraspMetrics(
            grip_force=grip_force,
            n_contacts=0,
            force_closure=False,
            epsilon=0.0,
            slip=float(np.linalg.norm(planar_velocity)),
            tilt=tilt,
            penetration=penetration,
        )

    touches = _Touches(
        particle[touching],
        np.ascontiguousarray(position[touching]),
        np.ascontiguousarray(normal[touching]),
        normal_force[touching],
        np.ascontiguousarray(velocity_rows[touching]),
    )
    points, fingers, normals, side = _merge_contacts(touches, float(min_horizontal_normal))
    slip = planar_slip(centre, planar_velocity, points[:, :2], fingers)
    epsilon = ferrari_canny(points[side, :2], normals[side, :2], mu, centre)
    return GraspMetrics(
        grip_force=grip_force,
        n_contacts=len(points),
        force_closure=epsilon > 0.0,
        epsilon=epsilon,
        slip=slip,
        tilt=tilt,
        penetration=penetration,
    )


@njit
def _merge_contacts(
    touches: _Touches, min_horizontal_normal: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """One contact per touching particle (:func:`grasp_metrics`), in increasing id.

    Returns:
        (points, velocities, normals, side): the force-weighted mean point (K, 3),
        particle velocity (K, 2) and normal (K, 3, not normalised) of each particle's
        rows, and whether it is a side contact (K,).
    """
    particle, position, normal, normal_force, velocity = touches
    ids = np.unique(particle)
    row_of = np.searchsorted(ids, particle)
    # Weights fall back to 1 for a particle touching without force, so that it still
    # has a point and a normal.
    total = np.zeros(len(ids))
    for r in range(len(particle)):
        total[row_of[r]] += normal_force[r]
    points = np.zeros((len(ids), 3))
    velocities = np.zeros((len(ids), 2))
    normals = np.zeros((len(ids), 3))
    weight_sum = np.zeros(len(ids))
    for r in range(len(particle)):
        i = row_of[r]
        weight = normal_force[r] if total[i] > 0.0 else 1.0
        weight_sum[i] += weight
        for d in range(3):
            points[i, d] += weight * position[r, d]
            normals[i, d] += weight * normal[r, d]
        for d in range(2):
            velocities[i, d] += weight * velocity[r, d]
    side = np.empty(len(ids), np.bool_)
    for i in range(len(ids)):
        points[i] /= weight_sum[i]
        velocities[i] /= weight_sum[i]
        horizontal = np.sqrt(normals[i, 0] ** 2 + normals[i, 1] ** 2)
        length = np.sqrt(normals[i, 0] ** 2 + normals[i, 1] ** 2 + normals[i, 2] ** 2)
        side[i] = horizontal >= max(min_horizontal_normal * length, 1e-300)
    return points, velocities, normals, side


def _velocity_rows(
    particle_velocities: ArrayLike, is_particle: NDArray[np.bool_]
) -> NDArray[np.float64]:
    """Planar particle velocities spread over every report row, (K, 2); 0 elsewhere."""
    given = np.asarray(particle_velocities, dtype=float)
    given = given.reshape(0, 2) if given.size == 0 else given
    n_rows, n_particle = is_particle.size, int(np.count_nonzero(is_particle))
    if (
        given.ndim != 2
        or given.shape[1] not in (2, 3)
        or given.shape[0] not in (n_particle, n_rows)
    ):
        raise ValueError(
            f"particle_velocities must have shape ({n_particle}, 2|3), one row per particle"
            f" contact of the report (or ({n_rows}, 2|3), one per row), got {given.shape}"
        )
    if given.shape[0] == n_rows:
        return given[:, :2].copy()
    rows = np.zeros((n_rows, 2))
    rows[is_particle] = given[:, :2]
    return rows
