"""Contact shapes: the rigid 2-D footprints that fingers, palms and objects press onto
the table, with their exact motion.

Every shape has a pose (a centre in metres and an angle in radians, world frame: x to
the right, y away from the viewer, angles counter-clockwise seen from above) and a
constant twist. The shape's own frame ("local" below) has its origin at the centre and
is turned by the angle.

Motion law. A twist is a linear velocity, an angular velocity ω and a *pivot*: a
point of the body (by default its centre). Over a time ``dt`` the pivot moves in a
straight line by ``v_pivot·dt`` while the body turns by ``ω·dt`` about it; a material
point at ``p`` goes to ``pivot + v_pivot·dt + R(ω·dt)(p − pivot)``. This is exact
for any ``dt`` (no first-order step) and composes: ``advance(a)`` then ``advance(b)``
equals ``advance(a + b)``. With the default pivot the centre moves in a straight line
at the linear velocity and the body spins about its centre. A hand that moves as one
rigid body gives all its shapes a common pivot (see :class:`graspenv.surface.Hand`),
so the distances between them stay exact over any number of frames. The
instantaneous velocity of a point is ``v + ω × (p − c)`` in both cases, where ``v`` is
the centre's velocity.
"""

from __future__ import annotations

import copy as _copy
import math
from abc import ABC, abstractmethod
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.surface import _checks

__all__ = [
    "ContactShape",
    "Fingertip",
    "HandEdge",
    "Palm",
    "PolygonShape",
    "Thumb",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
_Shape = TypeVar("_Shape", bound="ContactShape")


def _rotation(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _cross_z(omega: float, r: FloatArray) -> FloatArray:
    """ω ẑ × r for planar vectors r of shape (..., 2)."""
    return omega * np.stack([-r[..., 1], r[..., 0]], axis=-1)


class ContactShape(ABC):
    """A rigid planar shape on the table with a pose and a constant twist.

    Args:
        centre: metres, world frame, shape (2,).
        angle: radians, counter-clockwise from the world x axis to the local x axis.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s, counter-clockwise seen from above.

    Raises:
        ValueError: a value is not finite or has the wrong shape.
    """

    def __init__(
        self,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        self._centre = _checks.vector2(centre, "centre")
        self._angle = _checks.finite(angle, "angle")
        self._pivot = self._centre.copy()
        self._pivot_velocity = np.zeros(2)
        self._angular_velocity = 0.0
        self.set_twist(linear_velocity, angular_velocity)

    # -- shape-specific geometry, in the local frame ---------------------------------

    @abstractmethod
    def _local_outline(self, max_segment: float) -> FloatArray:
        """Counter-clockwise polygon, metres, local frame, edges <= max_segment."""

    @abstractmethod
    def _local_contains(self, local: FloatArray) -> BoolArray:
        """Whether points (metres, local frame, shape (N, 2)) are inside or on the edge."""

    @abstractmethod
    def _local_signed_distance(self, local: FloatArray) -> FloatArray:
        """Exact signed distance (metres, negative inside) of local points."""

    @property
    @abstractmethod
    def area(self) -> float:
        """Area of the footprint, square metres."""

    @property
    @abstractmethod
    def bounding_radius(self) -> float:
        """Largest distance from the centre to a point of the shape, metres."""

    # -- pose and twist --------------------------------------------------------------

    @property
    def centre(self) -> FloatArray:
        """Centre, metres, world frame, shape (2,) (a copy)."""
        return self._centre.copy()

    @centre.setter
    def centre(self, value: ArrayLike) -> None:
        self.set_pose(centre=value)

    @property
    def angle(self) -> float:
        """Orientation of the local x axis, radians (not wrapped)."""
        return self._angle

    @angle.setter
    def angle(self, value: float) -> None:
        self.set_pose(angle=value)

    @property
    def linear_velocity(self) -> FloatArray:
        """Current velocity of the centre, m/s, world frame, shape (2,)."""
        return self._pivot_velocity + _cross_z(self._angular_velocity, self._centre - self._pivot)

    @property
    def angular_velocity(self) -> float:
        """rad/s, counter-clockwise seen from above."""
        return self._angular_velocity

    @property
    def pivot(self) -> FloatArray:
        """The body point the finite motion turns about, metres, world frame, shape (2,)."""
        return self._pivot.copy()

    def set_pose(self, centre: ArrayLike | None = None, angle: float | None = None) -> None:
        """Place the shape, keeping its current centre velocity and angular velocity.

        The pivot is reset to the new centre: a placed shape no longer turns about a
        point chosen for its old pose.

        Args:
            centre: metres, world frame, shape (2,); None keeps the current centre.
            angle: radians; None keeps the current angle.
        """
        velocity = self.linear_velocity
        if centre is not None:
            self._centre = _checks.vector2(centre, "centre")
        if angle is not None:
            self._angle = _checks.finite(angle, "angle")
        self._pivot = self._centre.copy()
        self._pivot_velocity = velocity

    def set_translation(self, centre: FloatArray, angle: float, velocity: FloatArray) -> None:
        """Place the shape at ``centre`` and ``angle``, moving at ``velocity`` without
        spin (the pivot at the centre).

        The same state as ``set_pose(centre, angle)`` then ``set_twist(velocity, 0.0)``,
        for callers that computed the values themselves (the finger controller, every
        frame): metres, radians and m/s, world frame, finite float arrays of shape
        (2,), neither checked nor copied (the shape keeps them: pass new arrays).
        """
        self._centre = centre
        self._angle = angle
        self._pivot = centre.copy()
        self._pivot_velocity = velocity
        self._angular_velocity = 0.0

    def set_twist(
        self,
        linear: ArrayLike,
        angular: float,
        pivot: ArrayLike | None = None,
    ) -> None:
        """Set the constant twist used by :meth:`advance` and :meth:`displacement`.

        Args:
            linear: velocity of the centre, m/s, world frame, shape (2,).
            angular: angular velocity, rad/s, counter-clockwise seen from above.
            pivot: metres, world frame, shape (2,): the body point that moves in a
                straight line while the shape turns about it; None is the centre.
                Both choices give the same instantaneous velocities; they differ in
                the path over a finite ``dt`` (see the module docstring).
        """
        velocity = _checks.vector2(linear, "linear")
        omega = _checks.finite(angular, "angular")
        where = self._centre.copy() if pivot is None else _checks.vector2(pivot, "pivot")
        self._angular_velocity = omega
        self._pivot = where
        # The twist is stored at the pivot, the point that moves in a straight line.
        self._pivot_velocity = velocity - _cross_z(omega, self._centre - where)

    # -- motion ----------------------------------------------------------------------

    def advance(self, dt: float) -> None:
        """Move the shape by the exact rigid motion of its twist over ``dt`` seconds."""
        step = _checks.finite(dt, "dt")
        rotation = _rotation(self._angular_velocity * step)
        new_pivot = self._pivot + self._pivot_velocity * step
        self._centre = new_pivot + rotation @ (self._centre - self._pivot)
        self._pivot = new_pivot
        self._angle += self._angular_velocity * step

    def displacement(self, points: ArrayLike, dt: float) -> FloatArray:
        """True displacement over the next ``dt`` seconds of material points of the shape.

        Args:
            points: metres, world frame, shape (N, 2): where the points are now.
            dt: seconds.

        Returns:
            metres, world frame, shape (N, 2): where :meth:`advance` ``(dt)`` takes them
            minus where they are.
        """
        p = _checks.points(points, "points")
        step = _checks.finite(dt, "dt")
        rotation = _rotation(self._angular_velocity * step)
        relative = p - self._pivot
        return self._pivot_velocity * step + relative @ rotation.T - relative

    def point_velocity(self, points: ArrayLike) -> FloatArray:
        """Instantaneous velocity ``v + ω × (p − c)`` of material points.

        Args:
            points: metres, world frame, shape (N, 2).

        Returns:
            m/s, world frame, shape (N, 2).
        """
        p = _checks.points(points, "points")
        return self._pivot_velocity + _cross_z(self._angular_velocity, p - self._pivot)

    # -- frames ----------------------------------------------------------------------

    def to_local(self, points: ArrayLike) -> FloatArray:
        """Local coordinates of world points (metres, world frame, shape (N, 2))."""
        p = _checks.points(points, "points")
        return (p - self._centre) @ _rotation(self._angle)

    def to_world(self, local: ArrayLike) -> FloatArray:
        """World coordinates of local points (metres, local frame, shape (N, 2))."""
        q = _checks.points(local, "local")
        return q @ _rotation(self._angle).T + self._centre

    # -- geometry in the world frame -------------------------------------------------

    def outline(self, max_segment: float) -> FloatArray:
        """The boundary as a closed polygon.

        Vertices lie on the exact boundary; curved parts are inscribed chords.

        Args:
            max_segment: longest allowed edge, metres.

        Returns:
            metres, world frame, shape (N, 2), counter-clockwise seen from above, the
            last vertex joined to the first (not repeated).
        """
        segment = _checks.positive(max_segment, "max_segment")
        local = self._local_outline(segment)
        return local @ _rotation(self._angle).T + self._centre

    def contains(self, points: ArrayLike) -> BoolArray:
        """Whether world points (metres, shape (N, 2)) lie inside or on the shape."""
        return self._local_contains(self.to_local(points))

    def signed_distance(self, points: ArrayLike) -> FloatArray:
        """Exact Euclidean distance to the boundary, metres, negative inside.

        Args:
            points: metres, world frame, shape (N, 2).

        Returns:
            metres, shape (N,).
        """
        return self._local_signed_distance(self.to_local(points))

    def copy(self: _Shape) -> _Shape:
        """An independent copy of the same class (pose, twist and shape parameters)."""
        # Shapes hold only numbers and small arrays; a deep copy costs several times more.
        twin = _copy.copy(self)
        for key, value in vars(self).items():
            if isinstance(value, np.ndarray):
                setattr(twin, key, value.copy())
        return twin

    def _parameters(self) -> str:
        """The shape's own parameters for ``repr``."""
        return ""

    def __repr__(self) -> str:
        x, y = self._centre
        extra = self._parameters()
        return (
            f"{type(self).__name__}(centre=({x:.6g}, {y:.6g}), angle={self._angle:.6g}"
            f"{', ' + extra if extra else ''})"
        )


# -- ellipses ----------------------------------------------------------------------------


def _ellipse_outline(a: float, b: float, max_segment: float) -> FloatArray:
    # Along the parameter t the speed never exceeds max(a, b), so equal steps of
    # max_segment / max(a, b) keep every chord within max_segment.
    n = max(8, math.ceil(2.0 * math.pi * max(a, b) / max_segment))
    t = np.arange(n) * (2.0 * math.pi / n)
    return np.stack([a * np.cos(t), b * np.sin(t)], axis=-1)


def _ellipse_distance(a: float, b: float, local: FloatArray) -> FloatArray:
    """Signed distance to the ellipse x²/a² + y²/b² = 1 (Eberly's robust bisection)."""
    if a >= b:
        e0, e1 = a, b
        y0, y1 = np.abs(local[:, 0]), np.abs(local[:, 1])
    else:
        e0, e1 = b, a
        y0, y1 = np.abs(local[:, 1]), np.abs(local[:, 0])
    inside = (y0 / e0) ** 2 + (y1 / e1) ** 2 < 1.0
    distance = np.empty(len(local))

    # Near the major axis the root below lies within rounding of s = -1, where it
    # cannot be resolved; the on-axis formula is then off by at most y1 (distance is
    # 1-Lipschitz), that is by 1e-7 of the minor semi-axis.
    on_axis = y1 <= 1e-7 * e1
    # Off the major axis the nearest point is the root of one monotone function.
    off = ~on_axis
    if np.any(off):
        r0 = (e0 / e1) ** 2
        z0, z1 = y0[off] / e0, y1[off] / e1
        n0 = r0 * z0
        g = z0**2 + z1**2 - 1.0
        s0 = z1 - 1.0
        s1 = np.where(g < 0.0, 0.0, np.hypot(n0, z1) - 1.0)
        for _ in range(200):
            s = 0.5 * (s0 + s1)
            value = (n0 / (s + r0)) ** 2 + (z1 / (s + 1.0)) ** 2 - 1.0
            s0 = np.where(value > 0.0, s, s0)
            s1 = np.where(value > 0.0, s1, s)
            if np.all(s1 - s0 <= 1e-15 * np.maximum(1.0, np.abs(s))):
                break
        s = 0.5 * (s0 + s1)
        x0 = r0 * y0[off] / (s + r0)
        x1 = y1[off] / (s + 1.0)
        distance[off] = np.hypot(x0 - y0[off], x1 - y1[off])
    if np.any(on_axis):
        p0 = y0[on_axis]
        numer, denom = e0 * p0, e0 * e0 - e1 * e1
        # Inside, close to the centre, the nearest point leaves the axis (the evolute).
        near = numer < denom
        ratio = np.where(near, numer / np.where(denom > 0.0, denom, 1.0), 1.0)
        x0 = e0 * ratio
        x1 = e1 * np.sqrt(np.clip(1.0 - ratio**2, 0.0, None))
        distance[on_axis] = np.where(near, np.hypot(x0 - p0, x1), np.abs(p0 - e0))
    return np.where(inside, -distance, distance)


class Fingertip(ContactShape):
    """A fingertip: an ellipse whose size grows with how hard it presses.

    Local frame: y runs along the finger, x across it. Press law: a soft pad pressed
    harder flattens mostly along the finger, so at press ``p`` the along-finger
    semi-axis is ``radii[1]·(1 + spread·p)`` and the across-finger one
    ``radii[0]·(1 + spread·p/2)``. With the default ``spread`` of 0.3 a full press
    makes the tip 30 % longer and 15 % wider.

    Args:
        centre: metres, world frame, shape (2,).
        angle: radians, from the world x axis to the local x (across-finger) axis.
        radii: semi-axes (across, along) at zero press, metres.
        press: in [0, 1].
        spread: relative growth of the along-finger semi-axis at full press, >= 0.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s.

    Raises:
        ValueError: a radius is not > 0, ``press`` is outside [0, 1], ``spread`` < 0,
            or a value is not finite.
    """

    default_radii: tuple[float, float] = (0.006, 0.0075)

    def __init__(
        self,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        radii: ArrayLike | None = None,
        press: float = 0.0,
        spread: float = 0.3,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        super().__init__(centre, angle, linear_velocity, angular_velocity)
        rest = _checks.vector2(self.default_radii if radii is None else radii, "radii")
        if np.any(rest <= 0.0):
            raise ValueError(f"radii must both be > 0 metres, got {rest.tolist()}")
        self._radii = rest
        self._spread = _checks.non_negative(spread, "spread")
        self._press = 0.0
        self.press = press

    @property
    def radii(self) -> tuple[float, float]:
        """Semi-axes (across, along) at zero press, metres."""
        return (float(self._radii[0]), float(self._radii[1]))

    @property
    def spread(self) -> float:
        """Relative growth of the along-finger semi-axis at full press."""
        return self._spread

    @property
    def press(self) -> float:
        """How hard the tip presses, in [0, 1]."""
        return self._press

    @press.setter
    def press(self, value: float) -> None:
        number = _checks.finite(value, "press")
        if not 0.0 <= number <= 1.0:
            raise ValueError(f"press must be in [0, 1], got {value!r}")
        self._press = number

    @property
    def semi_axes(self) -> tuple[float, float]:
        """Semi-axes (across, along) at the current press, metres."""
        grow = self._spread * self._press
        return (
            float(self._radii[0] * (1.0 + 0.5 * grow)),
            float(self._radii[1] * (1.0 + grow)),
        )

    @property
    def area(self) -> float:
        a, b = self.semi_axes
        return math.pi * a * b

    @property
    def bounding_radius(self) -> float:
        return max(self.semi_axes)

    def _parameters(self) -> str:
        return f"radii=({self._radii[0]:.6g}, {self._radii[1]:.6g}), press={self._press:.6g}"

    def _local_outline(self, max_segment: float) -> FloatArray:
        return _ellipse_outline(*self.semi_axes, max_segment)

    def _local_contains(self, local: FloatArray) -> BoolArray:
        a, b = self.semi_axes
        result: BoolArray = (local[:, 0] / a) ** 2 + (local[:, 1] / b) ** 2 <= 1.0
        return result

    def _local_signed_distance(self, local: FloatArray) -> FloatArray:
        return _ellipse_distance(*self.semi_axes, local)


class Thumb(Fingertip):
    """A thumb tip: a :class:`Fingertip` with a larger default size (8.5 × 11 mm
    semi-axes at zero press)."""

    default_radii: tuple[float, float] = (0.0085, 0.011)


# -- rounded rectangles ------------------------------------------------------------------


class _RoundedBox(ContactShape):
    """A rectangle with rounded corners, centred on the shape's centre."""

    def __init__(
        self,
        half_extents: ArrayLike,
        corner_radius: float,
        centre: ArrayLike,
        angle: float,
        linear_velocity: ArrayLike,
        angular_velocity: float,
    ) -> None:
        super().__init__(centre, angle, linear_velocity, angular_velocity)
        half = _checks.vector2(half_extents, "half_extents")
        if np.any(half <= 0.0):
            raise ValueError(f"sizes must be > 0 metres, got {(2.0 * half).tolist()}")
        radius = _checks.non_negative(corner_radius, "corner_radius")
        if radius > float(half.min()):
            raise ValueError(
                f"corner_radius must be at most half the smaller side "
                f"({float(half.min())} m), got {corner_radius!r}"
            )
        self._half = half
        self._radius = radius

    def _parameters(self) -> str:
        hx, hy = self._half
        return f"size=({2 * hx:.6g}, {2 * hy:.6g}), corner_radius={self._radius:.6g}"

    @property
    def area(self) -> float:
        hx, hy = self._half
        return float(4.0 * hx * hy - (4.0 - math.pi) * self._radius**2)

    @property
    def bounding_radius(self) -> float:
        core = self._half - self._radius
        return float(np.hypot(*core) + self._radius)

    def _local_outline(self, max_segment: float) -> FloatArray:
        r = self._radius
        ax, ay = self._half - r
        # Eight pieces counter-clockwise from the top-right corner: arc, top side, arc,
        # left side, ... Each is sampled from its start, so sharp corners (r = 0) and
        # the ends of the sides are vertices.
        corner = np.array([[ax, ay], [-ax, ay], [-ax, -ay], [ax, -ay]])
        quarter = 0.5 * math.pi
        lengths = np.array([quarter * r, 2 * ax, quarter * r, 2 * ay] * 2)
        counts = np.ceil(lengths / max_segment).astype(int)
        piece = np.repeat(np.arange(8), counts)
        fraction = (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)) / (
            counts[piece]
        )
        which = piece // 2
        angle = quarter * (which + np.where(piece % 2 == 0, fraction, 1.0))
        on_circle = corner[which] + r * np.stack([np.cos(angle), np.sin(angle)], axis=-1)
        # Along a side the point slides from corner k's circle to corner k+1's.
        slide = (corner[(which + 1) % 4] - corner[which]) * fraction[:, None]
        result: FloatArray = np.where((piece % 2 == 0)[:, None], on_circle, on_circle + slide)
        return result

    def _local_signed_distance(self, local: FloatArray) -> FloatArray:
        q = np.abs(local) - (self._half - self._radius)
        outside = np.hypot(*np.clip(q, 0.0, None).T)
        inside = np.minimum(q.max(axis=1), 0.0)
        result: FloatArray = outside + inside - self._radius
        return result

    def _local_contains(self, local: FloatArray) -> BoolArray:
        result: BoolArray = self._local_signed_distance(local) <= 0.0
        return result


class Palm(_RoundedBox):
    """A flat palm: a rounded rectangle.

    Args:
        centre: metres, world frame, shape (2,).
        angle: radians, from the world x axis to the local x (across-hand) axis.
        size: full (width across the hand, length along it), metres.
        corner_radius: metres, at most half the smaller side.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s.
    """

    def __init__(
        self,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        size: ArrayLike = (0.075, 0.085),
        corner_radius: float = 0.02,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        half = 0.5 * _checks.vector2(size, "size")
        super().__init__(half, corner_radius, centre, angle, linear_velocity, angular_velocity)

    @property
    def size(self) -> tuple[float, float]:
        """Full (width, length), metres."""
        return (float(2.0 * self._half[0]), float(2.0 * self._half[1]))

    @property
    def corner_radius(self) -> float:
        """metres."""
        return self._radius


class HandEdge(_RoundedBox):
    """The edge of a hand laid on the table: a stadium (a long, thin rectangle with
    semicircular ends).

    Args:
        centre: metres, world frame, shape (2,).
        angle: radians, from the world x axis to the local x (across-edge) axis; the
            length runs along local y.
        length: end to end, metres.
        width: metres, less than or equal to ``length``.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s.
    """

    def __init__(
        self,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        length: float = 0.09,
        width: float = 0.02,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        long = _checks.positive(length, "length")
        wide = _checks.positive(width, "width")
        if wide > long:
            raise ValueError(f"width ({width!r} m) must not exceed length ({length!r} m)")
        super().__init__(
            (0.5 * wide, 0.5 * long), 0.5 * wide, centre, angle, linear_velocity, angular_velocity
        )

    @property
    def length(self) -> float:
        """End to end, metres."""
        return float(2.0 * self._half[1])

    @property
    def width(self) -> float:
        """metres."""
        return float(2.0 * self._half[0])


# -- polygons ----------------------------------------------------------------------------


def _signed_area(vertices: FloatArray) -> float:
    x, y = vertices[:, 0], vertices[:, 1]
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _edges_cross(vertices: FloatArray) -> bool:
    """Whether two non-adjacent edges of the closed polygon touch or cross."""
    m = len(vertices)
    if m < 4:
        return False
    p, q = vertices, np.roll(vertices, -1, axis=0)

    def orient(a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray:
        result: FloatArray = np.sign(
            (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        )
        return result

    i, j = np.triu_indices(m, k=2)
    keep = ~((i == 0) & (j == m - 1))  # the first and last edges share a vertex
    i, j = i[keep], j[keep]
    pi, qi, pj, qj = p[i], q[i], p[j], q[j]
    d1, d2 = orient(pi, qi, pj), orient(pi, qi, qj)
    d3, d4 = orient(pj, qj, pi), orient(pj, qj, qi)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)

    def within(a: FloatArray, b: FloatArray, c: FloatArray) -> NDArray[np.bool_]:
        """Whether c, known to lie on the line ab, lies on the segment ab."""
        result: NDArray[np.bool_] = np.all(
            (np.minimum(a, b) <= c) & (c <= np.maximum(a, b)), axis=1
        )
        return result

    # A vertex lying on another edge breaks simplicity as much as a crossing does.
    touching = (
        ((d1 == 0) & within(pi, qi, pj))
        | ((d2 == 0) & within(pi, qi, qj))
        | ((d3 == 0) & within(pj, qj, pi))
        | ((d4 == 0) & within(pj, qj, qi))
    )
    return bool(np.any(proper | touching))


class PolygonShape(ContactShape):
    """Any simple polygon, such as a card lying on the table.

    Args:
        vertices: metres, local frame (relative to the centre, before turning by
            ``angle``), shape (M, 2), M >= 3, either orientation, not closed (the last
            vertex is joined to the first), no edges crossing.
        centre: metres, world frame, shape (2,).
        angle: radians.
        linear_velocity: velocity of the centre, m/s, world frame, shape (2,).
        angular_velocity: rad/s.

    Raises:
        ValueError: fewer than 3 vertices, repeated consecutive vertices, zero area,
            crossing edges, or non-finite values.
    """

    def __init__(
        self,
        vertices: ArrayLike,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
        linear_velocity: ArrayLike = (0.0, 0.0),
        angular_velocity: float = 0.0,
    ) -> None:
        super().__init__(centre, angle, linear_velocity, angular_velocity)
        local = np.array(_checks.points(vertices, "vertices"))
        if len(local) < 3:
            raise ValueError(f"vertices must hold at least 3 points, got {len(local)}")
        steps = np.hypot(*(np.roll(local, -1, axis=0) - local).T)
        if np.any(steps == 0.0):
            raise ValueError("vertices must not repeat consecutively (zero-length edge)")
        area = _signed_area(local)
        if area == 0.0:
            raise ValueError("vertices enclose zero area")
        if _edges_cross(local):
            raise ValueError("vertices must form a simple polygon; two edges cross or touch")
        self._vertices = local if area > 0.0 else local[::-1].copy()
        self._area = abs(area)

    @classmethod
    def rectangle(
        cls,
        size: ArrayLike,
        centre: ArrayLike = (0.0, 0.0),
        angle: float = 0.0,
    ) -> PolygonShape:
        """A rectangle of full ``size`` (width along local x, height along local y),
        metres, centred on ``centre`` (metres, world frame, shape (2,))."""
        full = _checks.vector2(size, "size")
        if np.any(full <= 0.0):
            raise ValueError(f"size must be > 0 metres, got {full.tolist()}")
        hx, hy = 0.5 * full
        return cls([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]], centre, angle)

    @classmethod
    def from_world(cls, vertices: ArrayLike) -> PolygonShape:
        """A polygon from world vertices (metres, shape (M, 2)); its centre is the area
        centroid and its angle 0."""
        world = _checks.points(vertices, "vertices")
        if len(world) < 3:
            raise ValueError(f"vertices must hold at least 3 points, got {len(world)}")
        origin = world.mean(axis=0)
        relative = world - origin
        x, y = relative[:, 0], relative[:, 1]
        x1, y1 = np.roll(x, -1), np.roll(y, -1)
        cross = x * y1 - x1 * y
        area = 0.5 * float(np.sum(cross))
        if area == 0.0:
            raise ValueError("vertices enclose zero area")
        centroid = origin + np.array([np.sum((x + x1) * cross), np.sum((y + y1) * cross)]) / (
            6.0 * area
        )
        return cls(world - centroid, centroid)

    def _parameters(self) -> str:
        return f"vertices={self._vertices.round(6).tolist()}"

    @property
    def vertices(self) -> FloatArray:
        """Counter-clockwise vertices, metres, local frame, shape (M, 2) (a copy)."""
        return self._vertices.copy()

    @property
    def area(self) -> float:
        return self._area

    @property
    def bounding_radius(self) -> float:
        return float(np.hypot(*self._vertices.T).max())

    def _local_outline(self, max_segment: float) -> FloatArray:
        start = self._vertices
        edge = np.roll(start, -1, axis=0) - start
        counts = np.ceil(np.hypot(*edge.T) / max_segment).astype(int)
        owner = np.repeat(np.arange(len(start)), counts)
        offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        fraction = offsets / counts[owner]
        result: FloatArray = start[owner] + edge[owner] * fraction[:, None]
        return result

    def _local_contains(self, local: FloatArray) -> BoolArray:
        distance = self._edge_distance(local)
        # On an edge counts as inside, as for the other shapes.
        result: BoolArray = self._crossing_parity(local) | (distance == 0.0)
        return result

    def _local_signed_distance(self, local: FloatArray) -> FloatArray:
        distance = self._edge_distance(local)
        return np.where(self._crossing_parity(local), -distance, distance)

    def _crossing_parity(self, local: FloatArray) -> BoolArray:
        a = self._vertices[None, :, :]
        b = np.roll(self._vertices, -1, axis=0)[None, :, :]
        px, py = local[:, None, 0], local[:, None, 1]
        straddles = (a[..., 1] > py) != (b[..., 1] > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = a[..., 0] + (py - a[..., 1]) * (b[..., 0] - a[..., 0]) / (
                b[..., 1] - a[..., 1]
            )
        crossings = straddles & (px < x_cross)
        result: BoolArray = np.count_nonzero(crossings, axis=1) % 2 == 1
        return result

    def _edge_distance(self, local: FloatArray) -> FloatArray:
        a = self._vertices[None, :, :]
        edge = np.roll(self._vertices, -1, axis=0)[None, :, :] - a
        rel = local[:, None, :] - a
        t = np.clip(np.sum(rel * edge, axis=2) / np.sum(edge * edge, axis=2), 0.0, 1.0)
        gap = rel - t[..., None] * edge
        result: FloatArray = np.hypot(gap[..., 0], gap[..., 1]).min(axis=1)
        return result
