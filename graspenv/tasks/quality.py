"""Grasp quality of planar frictional contacts: the Ferrari–Canny epsilon and force
closure (numpy and the compiled hull; no physics).

Frames and units: any planar frame shared by the points and the centre (the world
frame's table plane in :func:`graspenv.tasks.metrics.grasp_metrics`), metres;
forces per unit normal force.

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

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.jit import njit

__all__ = ["ferrari_canny"]

# Relative to the largest wrench coordinate (about 1 with the default torque scale).
_RELATIVE_TOLERANCE = 1e-9


def ferrari_canny(
    points: ArrayLike,
    normals: ArrayLike,
    mu: float,
    centre: ArrayLike,
    torque_scale: float | None = None,
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
    Returns:
        Epsilon, dimensionless, >= 0; 0 without force closure, with fewer than two
        contacts, or for a wrench set flatter than the tolerance (1e-9 relative).

    Raises:
        ValueError: on mismatched shapes, a zero normal, ``mu < 0``,
            ``torque_scale <= 0``.
    """
    wrenches = _primitive_wrenches(points, normals, mu, centre, torque_scale)
    if wrenches is None:
        return 0.0
    return _epsilon_of_wrenches(wrenches)


def _primitive_wrenches(
    points: ArrayLike,
    normals: ArrayLike,
    mu: float,
    centre: ArrayLike,
    torque_scale: float | None,
    cone_edges: int = 2,
) -> NDArray[np.float64] | None:
    """Wrenches ``(f_x, f_y, τ/ρ)`` of every friction-cone sample, shape (K·E, 3).

    ``cone_edges`` forces are sampled across each cone, ``n + μ s t`` for s evenly
    spaced in [-1, 1], >= 2. In the plane the two edges span the cone exactly and
    wrenches are linear in the force, so more samples lie inside the hull and leave
    epsilon unchanged (tests/tasks/test_metrics.py checks it); :func:`ferrari_canny`
    uses two. None when there are fewer than two contacts (never force closure).
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
