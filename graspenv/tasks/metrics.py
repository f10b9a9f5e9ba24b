"""Grasp-stability metrics from the contacts on an object (numpy only).

Everything here works on plain arrays: :func:`grasp_metrics` reads any object with the
attribute names of :class:`graspenv.physics.ContactReport` (see
:class:`ContactArrays`), so this module never imports PyBullet.

Frames and units: world frame (origin at the table centre, z up), SI units (m, m/s,
N, rad); quaternions are (x, y, z, w). Grasp quality is planar: the table is the
plane of the grasp, so only the in-plane components of contact positions, normals and
velocities enter :func:`ferrari_canny` and the slip.

The planar Ferrari–Canny epsilon
--------------------------------
Each contact i at point p_i (relative to a centre c) with inward unit normal n_i and
friction coefficient μ can push with any force in its friction cone, the wedge
between the edges ``n_i ± μ t_i`` (t_i the unit tangent): unit normal force, as in
Ferrari and Canny (1992). A force f at p is the planar wrench ``(f_x, f_y, τ/ρ)``
with ``τ = p × f`` and ρ a characteristic length that makes torque commensurate with
force (default: the largest distance of a contact from the centre, so |τ/ρ| ≤ |f|).
The primitive wrenches are the cone edges of every contact; epsilon is the radius of
the largest ball about the origin inside their convex hull Q (the L1 quality: the
smallest disturbance wrench, in the worst direction, that a unit total of normal
force can resist). Epsilon is 0 when the origin is not strictly inside Q: then some
wrench cannot be resisted at all (no force closure).

For a convex polytope containing the origin, that radius is the smallest distance
from the origin to a facet plane, equivalently ``min over unit d of max_i w_i · d``
(the support function at the facet normals). It is computed exactly: an incremental
3-D convex hull of the primitive wrenches gives the facets, and epsilon is the
smallest support value over their outward normals. The hull is checked to contain
every wrench; should floating point ever break it, an exhaustive enumeration of the
facet planes through triples of wrenches gives the same answer more slowly. The only
approximation is a geometric tolerance of ``1e-9`` times the largest wrench
coordinate: a wrench set flatter than that (e.g. frictionless contacts whose normals
all pass through the centre) counts as having no interior, and an epsilon below it
is reported as 0.

Note that in the plane two antipodal contacts with friction *are* force closure
(Nguyen's two-finger condition: the line between the contacts lies inside both
friction cones): the opposing tangential friction forces form a couple that resists
torque about the axis normal to the plane. A torque about the line joining two point
contacts, which they cannot resist in 3-D, does not exist in the planar model.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.geometry import tilt_angle
from graspenv.jit import njit

__all__ = [
    "ContactArrays",
    "GraspMetrics",
    "coulomb_slip_force",
    "ferrari_canny",
    "force_closure",
    "grasp_metrics",
    "planar_slip",
    "rigid_velocity_at",
    "tilt_angle",
]

# Relative to the largest wrench coordinate (about 1 with the default torque scale).
_RELATIVE_TOLERANCE = 1e-9


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


@dataclass(frozen=True)
class GraspMetrics:
    """How well an object is held, from one physics step.

    Attributes:
        grip_force: sum of the normal forces of all particle contacts on the object,
            newtons (both sides of a squeeze, and particles pressing from above).
        n_contacts: number of distinct particles touching the object.
        force_closure: whether the particles' side contacts hold the object in force
            closure in the table plane (``epsilon > closure_tolerance``).
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


# -- Ferrari–Canny ----------------------------------------------------------------------


def ferrari_canny(
    points: ArrayLike,
    normals: ArrayLike,
    mu: float,
    centre: ArrayLike,
    torque_scale: float | None = None,
    cone_edges: int = 2,
) -> float:
    """Planar Ferrari–Canny epsilon (L1 quality) of a set of frictional point contacts.

    The radius of the largest ball about the origin inside the convex hull of the
    primitive wrenches ``(f_x, f_y, τ/ρ)`` of every contact's friction cone (see the
    module docstring), computed exactly from the hull's facets.

    Args:
        points: contact points, metres, world frame (or any planar frame shared with
            ``centre``), shape (K, 2).
        normals: contact normals pointing into the object, same frame, shape (K, 2);
            normalised here, must be non-zero.
        mu: Coulomb friction coefficient of the contacts, >= 0.
        centre: the point torques are taken about (the object's centre of mass),
            metres, shape (2,).
        torque_scale: ρ, metres, > 0; torques are divided by it. None: the largest
            distance of a contact point from ``centre`` (so the value does not
            change when the whole grasp is scaled).
        cone_edges: forces sampled across each friction cone, ``n + μ s t`` for s
            evenly spaced in [-1, 1], >= 2. In the plane the two edges span the cone
            exactly and wrenches are linear in the force, so more samples lie inside
            the hull and leave epsilon unchanged; the parameter keeps the interface of
            3-D cone discretisations.

    Returns:
        Epsilon, dimensionless, >= 0; 0 without force closure, with fewer than two
        contacts, or for a wrench set flatter than the tolerance (1e-9 relative).

    Raises:
        ValueError: on mismatched shapes, a zero normal, ``mu < 0``,
            ``torque_scale <= 0`` or ``cone_edges < 2``.
    """
    wrenches = _primitive_wrenches(points, normals, mu, centre, torque_scale, cone_edges)
    if wrenches is None:
        return 0.0
    return _epsilon_of_wrenches(wrenches)


def force_closure(
    points: ArrayLike,
    normals: ArrayLike,
    mu: float,
    centre: ArrayLike,
    torque_scale: float | None = None,
    cone_edges: int = 2,
    tolerance: float = 0.0,
) -> bool:
    """Whether planar frictional contacts hold an object in force closure.

    Force closure means the contacts can resist any planar wrench: the origin is
    strictly inside the convex hull of their primitive wrenches, i.e.
    :func:`ferrari_canny` is positive.

    Args:
        points: contact points, metres, shape (K, 2).
        normals: contact normals pointing into the object, shape (K, 2).
        mu: Coulomb friction coefficient, >= 0.
        centre: the point torques are taken about, metres, shape (2,).
        torque_scale: ρ, metres; see :func:`ferrari_canny`.
        cone_edges: forces sampled per friction cone; see :func:`ferrari_canny`.
        tolerance: the least epsilon counted as closure (epsilon must exceed it).
            0 (the default) already excludes configurations within floating-point
            tolerance of the boundary, which :func:`ferrari_canny` reports as 0; pass a
            positive margin for grasps that must survive noise.

    Returns:
        ``ferrari_canny(...) > tolerance``.
    """
    return ferrari_canny(points, normals, mu, centre, torque_scale, cone_edges) > tolerance


def _primitive_wrenches(
    points: ArrayLike,
    normals: ArrayLike,
    mu: float,
    centre: ArrayLike,
    torque_scale: float | None,
    cone_edges: int,
) -> NDArray[np.float64] | None:
    """Wrenches ``(f_x, f_y, τ/ρ)`` of every friction-cone sample, shape (K·E, 3).

    None when there are fewer than two contacts (never force closure).
    """
    p = np.asarray(points, dtype=float)
    n = np.asarray(normals, dtype=float)
    c = np.asarray(centre, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or n.shape != p.shape:
        raise ValueError(
            f"points and normals must both have shape (K, 2), got {p.shape} and {n.shape}"
        )
    if c.shape != (2,):
        raise ValueError(f"centre must have shape (2,), got {c.shape}")
    if not mu >= 0.0 or not math.isfinite(mu):
        raise ValueError(f"mu must be a finite friction coefficient >= 0, got {mu}")
    if torque_scale is not None and not torque_scale > 0.0:
        raise ValueError(f"torque_scale must be > 0 metres or None, got {torque_scale}")
    if cone_edges < 2:
        raise ValueError(f"cone_edges must be >= 2, got {cone_edges}")
    if p.shape[0] < 2:
        return None
    length = np.hypot(n[:, 0], n[:, 1])
    if not np.all(length > 0.0):
        raise ValueError(f"every normal must be non-zero; rows {np.flatnonzero(length == 0)}")
    return _wrenches(
        np.ascontiguousarray(p),
        np.ascontiguousarray(n),
        float(mu),
        c,
        -1.0 if torque_scale is None else float(torque_scale),
        int(cone_edges),
    )


@njit
def _wrenches(
    p: NDArray[np.float64],
    n: NDArray[np.float64],
    mu: float,
    c: NDArray[np.float64],
    torque_scale: float,
    cone_edges: int,
) -> NDArray[np.float64]:
    """:func:`_primitive_wrenches` once checked; ``torque_scale`` < 0 for None."""
    k = len(p)
    rho = torque_scale
    if rho < 0.0:
        rho = 0.0
        for i in range(k):
            rho = max(rho, np.sqrt((p[i, 0] - c[0]) ** 2 + (p[i, 1] - c[1]) ** 2))
    if rho == 0.0:  # every contact at the centre: no torques at all (a flat wrench set)
        rho = 1.0
    # Without friction the samples coincide; one per contact keeps the hull small.
    s = np.linspace(-1.0, 1.0, cone_edges) if mu > 0.0 else np.zeros(1)
    edges = len(s)
    out = np.empty((k * edges, 3))
    for i in range(k):
        length = np.sqrt(n[i, 0] ** 2 + n[i, 1] ** 2)
        nx, ny = n[i, 0] / length, n[i, 1] / length
        tx, ty = -ny, nx
        rx, ry = p[i, 0] - c[0], p[i, 1] - c[1]
        for e in range(edges):
            fx = nx + (mu * s[e]) * tx
            fy = ny + (mu * s[e]) * ty
            row = i * edges + e
            out[row, 0], out[row, 1] = fx, fy
            out[row, 2] = (rx * fy - ry * fx) / rho
    return out


def _epsilon_of_wrenches(wrenches: NDArray[np.float64]) -> float:
    """Distance from the origin to the boundary of the hull of ``wrenches`` (N, 3).

    0 when the origin is not strictly inside (or the hull is flat).
    """
    tol = _RELATIVE_TOLERANCE * max(1.0, float(np.max(np.abs(wrenches))))
    extremes = _torque_extremes(np.ascontiguousarray(wrenches, dtype=np.float64), tol)
    facets, status = _convex_hull_normals(extremes, tol)
    if status == _FLAT:
        return 0.0
    if status == _BROKEN:
        fallback = _facet_normals_by_enumeration(extremes, tol)
        if fallback is None:
            return 0.0
        facets = fallback
    # The support value at each outward facet normal is that facet plane's distance
    # from the origin (negative when the origin is beyond it).
    epsilon = _smallest_support(np.ascontiguousarray(wrenches, dtype=np.float64), facets)
    return epsilon if epsilon > tol else 0.0


@njit
def _smallest_support(wrenches: NDArray[np.float64], facets: NDArray[np.float64]) -> float:
    """min over facet normals n of max over wrenches w of w · n."""
    smallest = np.inf
    for f in range(len(facets)):
        largest = -np.inf
        for w in range(len(wrenches)):
            value = (
                wrenches[w, 0] * facets[f, 0]
                + wrenches[w, 1] * facets[f, 1]
                + wrenches[w, 2] * facets[f, 2]
            )
            largest = max(largest, value)
        smallest = min(smallest, largest)
    return float(smallest)


@njit
def _torque_extremes(wrenches: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """The wrenches that can be hull vertices among those sharing a force.

    Wrenches with one force (contacts on a flat face, same cone edge) lie on a
    vertical line in (f_x, f_y, τ/ρ), so all but the two torque extremes are convex
    combinations of those two and leave the hull unchanged. Forces are compared on a
    grid of spacing ``tol``: points a rounding apart count as one line, which moves
    the hull by at most ``tol``. The result runs line by line (forces in
    lexicographic order of their grid cells), lowest torque first.
    """
    n = len(wrenches)
    kx = np.empty(n, np.int64)
    ky = np.empty(n, np.int64)
    for i in range(n):
        kx[i] = np.int64(np.round(wrenches[i, 0] / tol))
        ky[i] = np.int64(np.round(wrenches[i, 1] / tol))
    order = np.argsort(wrenches[:, 2], kind="mergesort")
    order = order[np.argsort(ky[order], kind="mergesort")]
    order = order[np.argsort(kx[order], kind="mergesort")]
    keep = np.zeros(n, np.bool_)
    for r in range(n):
        i = order[r]
        first = r == 0 or kx[order[r - 1]] != kx[i] or ky[order[r - 1]] != ky[i]
        last = r == n - 1 or kx[order[r + 1]] != kx[i] or ky[order[r + 1]] != ky[i]
        keep[r] = first or last
    return wrenches[order[keep]]


def _cross(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise cross product of (M, 3) arrays (np.cross costs ~20 µs a call here)."""
    return np.column_stack(
        [
            u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
            u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0],
        ]
    )


# _convex_hull_normals' outcomes: a hull; points spanning less than three dimensions;
# a hull that failed its final check (floating point broke the construction).
_HULL, _FLAT, _BROKEN = 0, 1, 2


@njit
def _plane(
    points: NDArray[np.float64], a: int, b: int, c: int
) -> tuple[float, float, float, float]:
    """Unit normal ``(b − a) × (c − a)`` and offset n·a of one triangle; NaN for a
    degenerate one (which fails the hull's final check)."""
    ux = points[b, 0] - points[a, 0]
    uy = points[b, 1] - points[a, 1]
    uz = points[b, 2] - points[a, 2]
    vx = points[c, 0] - points[a, 0]
    vy = points[c, 1] - points[a, 1]
    vz = points[c, 2] - points[a, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    length = np.sqrt(nx * nx + ny * ny + nz * nz)
    if length == 0.0:
        return np.nan, np.nan, np.nan, np.nan
    nx, ny, nz = nx / length, ny / length, nz / length
    return nx, ny, nz, nx * points[a, 0] + ny * points[a, 1] + nz * points[a, 2]


# Vector helpers for the compiled hull: numba's np.dot, np.cross and np.linalg need
# SciPy's BLAS and LAPACK, which graspenv does not depend on.


@njit
def _dot3(u: NDArray[np.float64], v: NDArray[np.float64]) -> float:
    return float(u[0] * v[0] + u[1] * v[1] + u[2] * v[2])


@njit
def _length(u: NDArray[np.float64]) -> float:
    return float(np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]))


@njit
def _cross3(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.empty(3)
    out[0] = u[1] * v[2] - u[2] * v[1]
    out[1] = u[2] * v[0] - u[0] * v[2]
    out[2] = u[0] * v[1] - u[1] * v[0]
    return out


@njit
def _convex_hull_normals(
    points: NDArray[np.float64], tol: float
) -> tuple[NDArray[np.float64], int]:
    """Outward unit normals of the facets of the convex hull of 3-D points, (F, 3).

    Incremental construction: a starting tetrahedron of far-apart points, then each
    remaining point (farthest from the centroid first, so more of the later ones fall
    inside) replaces the facets it sees by a fan from their horizon to itself. Points
    within ``tol`` of a facet plane count as on it, so coplanar and collinear points
    add nothing.

    Returns:
        (normals, status): the facet normals (coplanar facets may repeat a plane) and
        ``_HULL``; or no normals and ``_FLAT`` when the points span less than three
        dimensions (beyond ``tol``), or ``_BROKEN`` when the hull fails its check.
    """
    count = len(points)
    none = np.zeros((0, 3))
    if count < 4:
        return none, _FLAT
    centre = np.zeros(3)
    for i in range(count):
        centre += points[i]
    centre /= count
    spread = np.empty(count)
    for i in range(count):
        spread[i] = _length(points[i] - centre)
    i0 = int(np.argmax(spread))
    far = np.empty(count)
    for i in range(count):
        far[i] = _length(points[i] - points[i0])
    i1 = int(np.argmax(far))
    axis = points[i1] - points[i0]
    axis_length = _length(axis)
    if axis_length <= tol:
        return none, _FLAT
    off_line = np.empty(count)
    for i in range(count):
        off_line[i] = _length(_cross3(points[i] - points[i0], axis)) / axis_length
    i2 = int(np.argmax(off_line))
    if off_line[i2] <= tol:
        return none, _FLAT
    plane = _cross3(axis, points[i2] - points[i0])
    plane /= _length(plane)
    height = np.empty(count)
    for i in range(count):
        height[i] = _dot3(points[i] - points[i0], plane)
    i3 = int(np.argmax(np.abs(height)))
    if abs(height[i3]) <= tol:
        return none, _FLAT

    # Facets live in preallocated rows; a replaced facet is marked dead, not removed.
    capacity = 8 * count + 8
    faces = np.zeros((capacity, 3), np.intp)
    normals = np.zeros((capacity, 3))
    offsets = np.zeros(capacity)
    alive = np.zeros(capacity, np.bool_)
    interior = (points[i0] + points[i1] + points[i2] + points[i3]) / 4.0
    start = ((i0, i1, i2), (i0, i1, i3), (i0, i2, i3), (i1, i2, i3))
    for f in range(4):
        a, b, c = start[f]
        nx, ny, nz, off = _plane(points, a, b, c)
        if nx * interior[0] + ny * interior[1] + nz * interior[2] - off > 0.0:
            b, c = c, b
            nx, ny, nz, off = -nx, -ny, -nz, -off
        faces[f, 0], faces[f, 1], faces[f, 2] = a, b, c
        normals[f, 0], normals[f, 1], normals[f, 2], offsets[f] = nx, ny, nz, off
        alive[f] = True
    used = 4
    seen = np.zeros(capacity, np.bool_)
    edges = np.empty((3 * capacity, 2), np.intp)
    horizon = np.empty((3 * capacity, 2), np.intp)
    for k in np.argsort(-spread, kind="mergesort"):
        if k in (i0, i1, i2, i3):
            continue
        any_seen = False
        for f in range(used):
            height_k = (
                normals[f, 0] * points[k, 0]
                + normals[f, 1] * points[k, 1]
                + normals[f, 2] * points[k, 2]
                - offsets[f]
            )
            seen[f] = alive[f] and height_k > tol
            any_seen = any_seen or seen[f]
        if not any_seen:
            continue
        # A horizon edge borders one seen facet: inside the seen patch every directed
        # edge a→b meets its reverse b→a in the neighbouring facet.
        n_edges = 0
        for f in range(used):
            if seen[f]:
                for e in range(3):
                    edges[n_edges, 0] = faces[f, e]
                    edges[n_edges, 1] = faces[f, (e + 1) % 3]
                    n_edges += 1
        n_horizon = 0
        for e in range(n_edges):
            inner = False
            for g in range(n_edges):
                if edges[g, 0] == edges[e, 1] and edges[g, 1] == edges[e, 0]:
                    inner = True
                    break
            if not inner:
                horizon[n_horizon, 0] = edges[e, 0]
                horizon[n_horizon, 1] = edges[e, 1]
                n_horizon += 1
        for f in range(used):
            if seen[f]:
                alive[f] = False
        if used + n_horizon > capacity:  # compact the live facets first
            kept = 0
            for f in range(used):
                if alive[f]:
                    faces[kept] = faces[f]
                    normals[kept] = normals[f]
                    offsets[kept] = offsets[f]
                    kept += 1
            alive[:] = False
            alive[:kept] = True
            used = kept
            if used + n_horizon > capacity:  # more facets than a hull can have
                return none, _BROKEN
        # Keeping each horizon edge's direction keeps every facet's winding outward.
        for e in range(n_horizon):
            a, b = horizon[e, 0], horizon[e, 1]
            faces[used, 0], faces[used, 1], faces[used, 2] = a, b, k
            nx, ny, nz, off = _plane(points, a, b, k)
            normals[used, 0], normals[used, 1], normals[used, 2] = nx, ny, nz
            offsets[used] = off
            alive[used] = True
            used += 1

    result = normals[:used][alive[:used]]
    result_offsets = offsets[:used][alive[:used]]
    # A valid hull has every point inside every facet and the interior point strictly
    # inside; floating point can in principle break an incremental hull.
    for f in range(len(result)):
        if not np.all(np.isfinite(result[f])):
            return none, _BROKEN
        if _dot3(result[f], interior) - result_offsets[f] >= 0.0:
            return none, _BROKEN
        for i in range(count):
            if _dot3(result[f], points[i]) - result_offsets[f] > 100.0 * tol:
                return none, _BROKEN
    return result, _HULL


def _facet_normals_by_enumeration(
    points: NDArray[np.float64], tol: float
) -> NDArray[np.float64] | None:
    """The hull's facet normals found by testing the plane through every triple.

    Exhaustive, O(N⁴): the fallback of :func:`_convex_hull_normals` and its check.
    A plane through three points is a facet plane when no point lies beyond it by more
    than ``tol``; its outward side is the one with no points.

    Returns:
        Outward unit normals (F, 3), or None when the points span less than three
        dimensions.
    """
    centred = points - points.mean(axis=0)
    if points.shape[0] < 4 or np.linalg.svd(centred, compute_uv=False)[-1] <= tol:
        return None
    found = []
    triples = np.array(list(itertools.combinations(range(points.shape[0]), 3)), dtype=np.intp)
    for chunk in np.array_split(triples, max(1, len(triples) // 4096)):
        a, b, c = points[chunk[:, 0]], points[chunk[:, 1]], points[chunk[:, 2]]
        normal = _cross(b - a, c - a)
        length = np.linalg.norm(normal, axis=1)
        keep = length > tol
        normal = normal[keep] / length[keep, None]
        side = points @ normal.T - np.einsum("ij,ij->i", normal, a[keep])
        below = np.all(side <= tol, axis=0)
        above = np.all(side >= -tol, axis=0)
        found.append(np.concatenate([normal[below & ~above], -normal[above & ~below]]))
    normals = np.concatenate(found)
    return normals if len(normals) else None


# -- slip, tilt and the Coulomb limit ---------------------------------------------------


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


# -- the whole set -----------------------------------------------------------------------


def grasp_metrics(
    report: ContactArrays,
    object_position: ArrayLike,
    object_quaternion: ArrayLike,
    object_linear_velocity: ArrayLike,
    object_angular_velocity: ArrayLike,
    particle_velocities: ArrayLike,
    mu: float,
    *,
    torque_scale: float | None = None,
    cone_edges: int = 2,
    closure_tolerance: float = 0.0,
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
        torque_scale: ρ for :func:`ferrari_canny`, metres; None: the farthest side
            contact from the centre.
        cone_edges: forces sampled per friction cone, see :func:`ferrari_canny`.
        closure_tolerance: least epsilon counted as force closure.
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

    points, fingers, normals, side = _merge_contacts(
        particle[touching],
        np.ascontiguousarray(position[touching]),
        np.ascontiguousarray(normal[touching]),
        normal_force[touching],
        np.ascontiguousarray(velocity_rows[touching]),
        float(min_horizontal_normal),
    )
    slip = planar_slip(centre, planar_velocity, points[:, :2], fingers)
    epsilon = ferrari_canny(
        points[side, :2],
        normals[side, :2],
        mu,
        centre,
        torque_scale=torque_scale,
        cone_edges=cone_edges,
    )
    return GraspMetrics(
        grip_force=grip_force,
        n_contacts=len(points),
        force_closure=epsilon > closure_tolerance,
        epsilon=epsilon,
        slip=slip,
        tilt=tilt,
        penetration=penetration,
    )


@njit
def _merge_contacts(
    particle: NDArray[np.int64],
    position: NDArray[np.float64],
    normal: NDArray[np.float64],
    normal_force: NDArray[np.float64],
    velocity: NDArray[np.float64],
    min_horizontal_normal: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """One contact per touching particle (:func:`grasp_metrics`), in increasing id.

    Returns:
        (points, velocities, normals, side): the force-weighted mean point (K, 3),
        particle velocity (K, 2) and normal (K, 3, not normalised) of each particle's
        rows, and whether it is a side contact (K,).
    """
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
