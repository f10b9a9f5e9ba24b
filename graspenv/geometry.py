"""Geometry shared by every stage: frames, yaw and tilt, object extents and footprints,
and point sets laid end to end."""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import accumulate
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from graspenv.config import ObjectConfig
from graspenv.jit import njit

__all__ = [
    "SHAPE_CODES",
    "Polylines",
    "bounding_radius",
    "bounds_of",
    "convex_hull",
    "footprint",
    "footprint_depths",
    "footprint_sides",
    "inscribed_radius",
    "less_along",
    "not_into",
    "reach_from",
    "rotate",
    "shoelace",
    "tilt_angle",
    "wrap_angle",
    "yaw_of",
    "yaw_step",
]


def yaw_of(quaternion: Sequence[float] | NDArray[np.float64]) -> float:
    """Rotation about z of a quaternion (x, y, z, w), radians in (-π, π]."""
    x, y, z, w = (float(v) for v in quaternion)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def wrap_angle(angle: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Angles wrapped into [-π, π), elementwise (goal errors of batches of poses)."""
    return np.mod(np.asarray(angle, dtype=float) + math.pi, 2 * math.pi) - math.pi


def yaw_step(now: float, before: float) -> float:
    """How far a yaw turned from ``before`` to ``now``, radians in [-π, π]: the
    shorter way round, so summing the steps of a motion unwraps its yaw."""
    return math.remainder(now - before, 2 * math.pi)


def shoelace(points: NDArray[np.float64]) -> float:
    """Signed area of a closed polygon's vertices, shape (N, 2), positive when they
    run counter-clockwise; taken about the first vertex, so coordinates far from the
    origin lose no precision to the cancelling cross products."""
    rel = points[1:] - points[0]
    return 0.5 * float(np.sum(rel[:-1, 0] * rel[1:, 1] - rel[:-1, 1] * rel[1:, 0]))


def rotate(points: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Points turned counter-clockwise by ``angle`` radians about the origin, (N, 2)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(points, dtype=float) @ np.array([[c, s], [-s, c]])


def bounding_radius(config: ObjectConfig) -> float:
    """The distance from an object's centre to its farthest point, metres.

    A box's half diagonal, a sphere's radius, a cylinder's rim corner: the lever arm
    of the fastest point when the object spins about its centre.
    """
    if config.shape == "box":
        return 0.5 * math.sqrt(sum(s * s for s in config.size))
    if config.shape == "sphere":
        return config.size[0]
    radius, height = config.size
    return math.hypot(radius, 0.5 * height)


def inscribed_radius(config: ObjectConfig) -> float:
    """The smallest distance from an object's centre to its surface, metres.

    Also its lowest possible resting height: the centre of an object lying on the
    table in any orientation is at least this high.
    """
    if config.shape == "box":
        return 0.5 * min(config.size)
    if config.shape == "sphere":
        return config.size[0]
    radius, height = config.size
    return min(radius, 0.5 * height)


def footprint(obj: ObjectConfig, position: NDArray[np.float64], yaw: float) -> NDArray[np.float64]:
    """An object's outline seen from above, metres, world frame, shape (N, 2)."""
    if obj.shape == "box":
        hx, hy = obj.size[0] / 2, obj.size[1] / 2
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    else:
        angle = np.linspace(0.0, 2 * math.pi, 48, endpoint=False)
        local = obj.size[0] * np.column_stack([np.cos(angle), np.sin(angle)])
    return rotate(local, yaw) + position[:2]


def tilt_angle(quaternion: Sequence[float] | NDArray[np.float64]) -> float:
    """Angle between a body's z axis and the world's z axis.

    Args:
        quaternion: orientation (x, y, z, w), normalised here, shape (4,).

    Returns:
        Radians in [0, π]; yaw alone gives 0.
    """
    x, y, z, w = np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion)
    # Third column of the rotation matrix: the body's z axis in the world frame.
    axis_x = 2.0 * (x * z + w * y)
    axis_y = 2.0 * (y * z - w * x)
    axis_z = 1.0 - 2.0 * (x * x + y * y)
    return math.atan2(math.hypot(axis_x, axis_y), axis_z)


class Polylines(NamedTuple):
    """Several point sets laid end to end (contours, outlines, a contact's points):
    set c is ``points[bounds[c]:bounds[c + 1]]``. The compiled stages take and return
    them as one argument.

    Attributes:
        points: the sets one after another, shape (T, 2), in the frame they are
            given in (metres, world frame, for contacts).
        bounds: where each set starts, and the total (:func:`bounds_of`), (C + 1,).
    """

    points: NDArray[np.float64]
    bounds: NDArray[np.intp]


def bounds_of(sizes: Sequence[int] | NDArray[np.intp]) -> NDArray[np.intp]:
    """Where each of several arrays laid end to end starts, and the total.

    The batch functions of :mod:`graspenv.contacts` take every contour of a frame as
    one array and these bounds (:class:`Polylines`): contour c is
    ``points[bounds[c]:bounds[c + 1]]``.

    Args:
        sizes: the arrays' lengths, (C,).

    Returns:
        Shape (C + 1,): 0, then the running totals.
    """
    bounds = np.zeros(len(sizes) + 1, dtype=np.intp)
    # A running sum in Python: a frame has a few contacts, and numpy's cumsum costs
    # more than the sum itself at that size.
    bounds[1:] = list(accumulate(sizes))
    return bounds


@njit
def reach_from(centres: NDArray[np.float64], sets: Polylines) -> NDArray[np.float64]:
    """How far each of several point sets reaches from its centre (the radius of the
    smallest disc about the centre that holds the set).

    Args:
        centres: one point per set, shape (C, 2).
        sets: the point sets, same frame.

    Returns:
        Each set's largest distance from its centre, same unit, shape (C,); 0 for
        an empty set.
    """
    points, bounds = sets
    reach = np.zeros(len(centres))
    for c in range(len(centres)):
        for i in range(bounds[c], bounds[c + 1]):
            distance = np.hypot(points[i, 0] - centres[c, 0], points[i, 1] - centres[c, 1])
            reach[c] = max(reach[c], distance)
    return reach


#: Object shapes as the footprint kernel numbers them (``ObjectConfig.shape``).
SHAPE_CODES = {"box": 0, "sphere": 1, "cylinder": 2}
# A cylinder whose top leans less than this off its base (metres) casts the shadow of
# its end disc: 1 µm, far below the penetration margin and the culling margin.
_UPRIGHT_LEAN = 1e-6
# Points on the rim of a leaning cylinder's end discs that draw its footprint.
_RIM_POINTS = 32


@njit
def footprint_depths(
    points: NDArray[np.float64],
    shapes: NDArray[np.int64],
    sizes: NDArray[np.float64],
    positions: NDArray[np.float64],
    rotations: NDArray[np.float64],
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """How deep each point lies inside the nearest object's footprint (its shadow on
    the table, in the object's current pose).

    A box's shadow is the Minkowski sum of its three half-axes projected on the
    table (a zonogon: a hexagon or a rectangle): for each projected axis g_i, two of
    its edges are parallel to g_i, at ±h_i = Σ_j |n_i · g_j| along its normal n_i, and
    the depth is the smallest h_i − |n_i · p| over the axes that do not project to a
    point. A sphere's is its disc; an upright cylinder's its end disc; a leaning
    cylinder's the convex hull of its two end discs' rims.

    Args:
        points: metres, world frame, shape (N, 2).
        shapes: :data:`SHAPE_CODES` of each object, shape (O,).
        sizes: ``ObjectConfig.size`` of each object, padded with zeros, (O, 3).
        positions: object centres, metres, world frame, (O, 3).
        rotations: object rotation matrices, row-major, (O, 9).

    Returns:
        (object, depth): the index of the object holding each point deepest (the one
        it lies least far outside of, outside every footprint; -1 without objects),
        and that depth, metres, negative outside; shapes (N,). Outside a box the
        depth is minus the distance beyond its farthest edge *line*, never more than
        the true distance: a point is never nearer an object than its depth says.
    """
    n = len(points)
    owner = np.full(n, -1, np.int64)
    best = np.full(n, -np.inf)
    for o in range(len(shapes)):
        depth = np.empty(n)
        r = rotations[o]
        cx, cy = positions[o, 0], positions[o, 1]
        if shapes[o] == 0:
            normals, reach, count = _box_edges(r, sizes[o])
            for k in range(n):
                depth[k] = _nearest_edge(
                    normals, reach, count, points[k, 0] - cx, points[k, 1] - cy
                )[0]
        elif _is_disc(shapes[o], r, sizes[o]):
            radius = sizes[o, 0]
            for k in range(n):
                depth[k] = radius - np.hypot(points[k, 0] - cx, points[k, 1] - cy)
        else:
            depth[:] = _leaning_cylinder_depth(points, sizes[o, 0], sizes[o, 1], r, cx, cy)
        for k in range(n):
            if depth[k] > best[k]:
                best[k] = depth[k]
                owner[k] = o
    return owner, best


@njit
def _is_disc(shape: int, r: NDArray[np.float64], size: NDArray[np.float64]) -> bool:
    """Whether an object's footprint is a disc: a sphere's, or an upright (or nearly
    upright, :data:`_UPRIGHT_LEAN`) cylinder's; not a box (code 0)."""
    return shape == 1 or (shape != 0 and np.hypot(r[2], r[5]) * size[1] < _UPRIGHT_LEAN)


@njit
def _box_edges(
    r: NDArray[np.float64], size: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """A box's shadow on the table (:func:`footprint_depths`): the unit normals of its
    edge pairs, (3, 2), their distances from the centre, (3,), and how many of the
    three rows are used (an axis seen end-on has no edges of its own)."""
    normals = np.zeros((3, 2))
    reach = np.zeros(3)
    axes = np.empty((3, 2))
    for i in range(3):
        axes[i, 0] = r[i] * size[i] / 2
        axes[i, 1] = r[3 + i] * size[i] / 2
    count = 0
    for i in range(3):
        length = np.hypot(axes[i, 0], axes[i, 1])
        if length <= 1e-12:
            continue
        nx, ny = -axes[i, 1] / length, axes[i, 0] / length
        normals[count, 0], normals[count, 1] = nx, ny
        for j in range(3):
            reach[count] += abs(nx * axes[j, 0] + ny * axes[j, 1])
        count += 1
    return normals, reach, count


@njit
def _nearest_edge(
    normals: NDArray[np.float64], reach: NDArray[np.float64], count: int, dx: float, dy: float
) -> tuple[float, int]:
    """How deep a point (``dx``, ``dy`` from the centre) lies inside a box's shadow
    (:func:`_box_edges`), and which edge pair is the nearest (-1 with none)."""
    depth, nearest = np.inf, -1
    for i in range(count):
        gap = reach[i] - abs(dx * normals[i, 0] + dy * normals[i, 1])
        if gap < depth:
            depth, nearest = gap, i
    return depth, nearest


@njit
def footprint_sides(
    points: NDArray[np.float64],
    shapes: NDArray[np.int64],
    sizes: NDArray[np.float64],
    positions: NDArray[np.float64],
    rotations: NDArray[np.float64],
    near: float,
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The nearest object's side at each point: :func:`footprint_depths`' object and
    depth, and the side's table-plane outward normal there (the normal of the box
    shadow's edge nearest the point, or the radial direction of a sphere's or an
    upright cylinder's disc).

    Args:
        points, shapes, sizes, positions, rotations: as :func:`footprint_depths`.
        near: points farther outside every footprint than this, metres, get no
            normal.

    Returns:
        (object, depth, normal): the first two as :func:`footprint_depths` gives
        them, then unit normals pointing out of the object, shape (N, 2) (on a box's
        centre line through an edge pair, either of the pair's); zero where there
        is none: a point farther than ``near`` from every object, at a disc's
        centre, or by a leaning cylinder (whose shadow is a hull with no single side
        to follow).
    """
    owner, depth = footprint_depths(points, shapes, sizes, positions, rotations)
    out = np.zeros((len(points), 2))
    for o in range(len(shapes)):
        r = rotations[o]
        is_box = shapes[o] == 0
        if not is_box and not _is_disc(shapes[o], r, sizes[o]):
            continue  # a leaning cylinder
        normals, reach, count = (
            _box_edges(r, sizes[o]) if is_box else (np.zeros((3, 2)), np.zeros(3), 0)
        )
        for k in range(len(points)):
            if owner[k] != o or depth[k] < -near:
                continue
            dx, dy = points[k, 0] - positions[o, 0], points[k, 1] - positions[o, 1]
            if is_box:
                nearest = _nearest_edge(normals, reach, count, dx, dy)[1]
                if nearest >= 0:
                    nx, ny = normals[nearest, 0], normals[nearest, 1]
                    sign = -1.0 if dx * nx + dy * ny < 0.0 else 1.0
                    out[k, 0], out[k, 1] = sign * nx, sign * ny
            else:
                length = np.hypot(dx, dy)
                if length > 0.0:
                    out[k, 0], out[k, 1] = dx / length, dy / length
    return owner, depth, out


@njit
def _leaning_cylinder_depth(
    points: NDArray[np.float64],
    radius: float,
    height: float,
    r: NDArray[np.float64],
    cx: float,
    cy: float,
) -> NDArray[np.float64]:
    """Depth in the shadow of a leaning cylinder: the hull of its rims, (N,)."""
    rim = np.empty((2 * _RIM_POINTS, 2))
    for e in range(2):
        z = (e - 0.5) * height
        for k in range(_RIM_POINTS):
            angle = 2.0 * np.pi * k / _RIM_POINTS
            x, y = radius * np.cos(angle), radius * np.sin(angle)
            rim[e * _RIM_POINTS + k, 0] = r[0] * x + r[1] * y + r[2] * z
            rim[e * _RIM_POINTS + k, 1] = r[3] * x + r[4] * y + r[5] * z
    hull = convex_hull(rim)
    depth = np.full(len(points), -np.inf)
    if len(hull) < 3:
        return depth
    for k in range(len(points)):
        px, py = points[k, 0] - cx, points[k, 1] - cy
        value = np.inf
        for i in range(len(hull)):
            j = (i + 1) % len(hull)
            ex, ey = hull[j, 0] - hull[i, 0], hull[j, 1] - hull[i, 1]
            length = np.hypot(ex, ey)
            # Distance from the edge line towards the inside (counter-clockwise hull).
            value = min(value, ((px - hull[i, 0]) * -ey + (py - hull[i, 1]) * ex) / length)
        depth[k] = value
    return depth


@njit
def convex_hull(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Counter-clockwise convex hull of 2-D points (Andrew's monotone chain), (M, 2).

    Compiled and exact in its orientation tests, for the per-frame footprints;
    collinear points are left out.
    """
    # Sort by x, then y: a stable sort by x after one by y.
    order = np.argsort(points[:, 1], kind="mergesort")
    order = order[np.argsort(points[order, 0], kind="mergesort")]
    n = len(points)
    chain = np.empty((2 * n, 2))
    size = 0
    for sweep in range(2):
        start = size
        for t in range(n):
            p = points[order[t] if sweep == 0 else order[n - 1 - t]]
            while size >= start + 2:
                ax, ay = chain[size - 2, 0], chain[size - 2, 1]
                bx, by = chain[size - 1, 0], chain[size - 1, 1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 1e-15:
                    break
                size -= 1
            chain[size, 0], chain[size, 1] = p[0], p[1]
            size += 1
        size -= 1  # the last point of each half is the first of the other
    return chain[:size].copy()


def less_along(vectors: NDArray[np.float64], unit: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each row of ``vectors`` less its part along the same row of ``unit`` (a unit
    vector or zero), shape (N, 2)."""
    return vectors - _along(vectors, unit)[:, None] * unit


def not_into(offset: NDArray[np.float64], outward: NDArray[np.float64]) -> NDArray[np.float64]:
    """Offsets (metres, (N, 2)) less any part of each into its side: along the side's
    outward normal (unit, or a zero row where there is no side), a negative part is
    taken away and a positive one kept."""
    return offset - np.minimum(_along(offset, outward), 0.0)[:, None] * outward


def _along(vectors: NDArray[np.float64], unit: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each row's component along the same row of ``unit``, shape (N,)."""
    return np.einsum("ij,ij->i", vectors, unit)
