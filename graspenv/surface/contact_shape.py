"""The contact shape: a rigid 2-D footprint on the table, with its exact motion.

:class:`ContactShape` is the base of every shape (graspenv/surface/shapes.py lists
them): the pose, the twist and the motion law below, and the outline, area and
point tests that a concrete shape answers in its own frame.

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

__all__ = ["BoolArray", "ContactShape", "FloatArray"]

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
        self, centre: ArrayLike, angle: float, linear_velocity: ArrayLike, angular_velocity: float
    ) -> None:
        # No defaults here: each concrete shape's signature has its own (and its
        # own order of arguments), and always passes all four.
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
