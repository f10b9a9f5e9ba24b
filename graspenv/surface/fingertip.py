"""Fingertips and thumbs: ellipses whose size grows with how hard they press.

:class:`Fingertip` (and :class:`Thumb`, a wider one) is a
:class:`~graspenv.surface.contact_shape.ContactShape` whose outline is an ellipse;
the signed distance to it is exact (Eberly's robust bisection).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from graspenv.surface import _checks
from graspenv.surface.contact_shape import BoolArray, ContactShape, FloatArray

__all__ = ["Fingertip", "Thumb"]


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
