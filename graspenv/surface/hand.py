"""A hand on the table: named contact shapes, each touching the table or lifted."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.surface import _checks
from graspenv.surface.shapes import ContactShape

__all__ = ["Hand"]


class Hand:
    """An ordered, named collection of contact shapes with touch flags.

    Lifted shapes keep moving with their twist but are not rendered. Iterating yields
    ``(name, shape, touching)`` in insertion order; ``hand[name]`` is the shape itself
    (not a copy), so ``hand["index"].set_twist(...)`` moves one finger.

    Args:
        shapes: ``{name: shape}`` or ``(name, shape)`` pairs, all touching; more can be
            added with :meth:`add`.

    Raises:
        ValueError: a name is empty or repeated, or a value is not a ContactShape.
    """

    def __init__(
        self,
        shapes: Mapping[str, ContactShape] | Iterable[tuple[str, ContactShape]] | None = None,
    ) -> None:
        self._shapes: dict[str, ContactShape] = {}
        self._touching: dict[str, bool] = {}
        pairs = shapes.items() if isinstance(shapes, Mapping) else (shapes or ())
        for name, shape in pairs:
            self.add(name, shape)

    def add(self, name: str, shape: ContactShape, touching: bool = True) -> None:
        """Add a shape (kept by reference) under a new name."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"a shape name must be a non-empty string, got {name!r}")
        if name in self._shapes:
            raise ValueError(f"a shape named {name!r} is already in the hand")
        if not isinstance(shape, ContactShape):
            raise ValueError(f"shape {name!r} must be a ContactShape, got {type(shape).__name__}")
        self._shapes[name] = shape
        self._touching[name] = bool(touching)

    def remove(self, name: str) -> ContactShape:
        """Take a shape out of the hand and return it."""
        shape = self[name]
        del self._shapes[name]
        del self._touching[name]
        return shape

    # -- access ----------------------------------------------------------------------

    def __getitem__(self, name: str) -> ContactShape:
        self._require(name)
        return self._shapes[name]

    def _require(self, name: str) -> None:
        if name not in self._shapes:
            raise KeyError(f"no shape named {name!r}; the hand has {self.names}")

    def __contains__(self, name: object) -> bool:
        return name in self._shapes

    def __len__(self) -> int:
        return len(self._shapes)

    def __iter__(self) -> Iterator[tuple[str, ContactShape, bool]]:
        for name, shape in self._shapes.items():
            yield name, shape, self._touching[name]

    @property
    def names(self) -> tuple[str, ...]:
        """Shape names in insertion order."""
        return tuple(self._shapes)

    def is_touching(self, name: str) -> bool:
        """Whether the named shape is down on the table."""
        self._require(name)
        return self._touching[name]

    def set_touching(self, name: str, touching: bool) -> None:
        """Put the named shape down (True) or lift it (False)."""
        self._require(name)
        self._touching[name] = bool(touching)

    def touching_shapes(self) -> list[ContactShape]:
        """The shapes that are down, in order (what the table sees)."""
        return [shape for name, shape in self._shapes.items() if self._touching[name]]

    # -- motion ----------------------------------------------------------------------

    def move_rigid(
        self,
        linear_velocity: ArrayLike,
        angular_velocity: float,
        pivot: ArrayLike,
        names: Iterable[str] | None = None,
    ) -> None:
        """Make shapes move as one rigid body turning about ``pivot``.

        Each shape gets ``v_i = v + ω × (c_i − pivot)`` and ``ω_i = ω``, with the
        pivot as the common point its finite motion turns about, so the distances
        between the shapes (and every point on them) stay exact over any ``dt``.

        Args:
            linear_velocity: velocity of the pivot, m/s, world frame, shape (2,).
            angular_velocity: rad/s, counter-clockwise seen from above.
            pivot: metres, world frame, shape (2,); it moves with the group.
            names: the shapes that move together; None is all of them.
        """
        velocity = _checks.vector2(linear_velocity, "linear_velocity")
        omega = _checks.finite(angular_velocity, "angular_velocity")
        centre = _checks.vector2(pivot, "pivot")
        chosen = self.names if names is None else tuple(names)
        shapes = [self[name] for name in chosen]
        for shape in shapes:
            r = shape.centre - centre
            shape.set_twist(velocity + omega * np.array([-r[1], r[0]]), omega, pivot=centre)

    def stop(self) -> None:
        """Zero every shape's twist."""
        for shape in self._shapes.values():
            shape.set_twist((0.0, 0.0), 0.0)

    def advance(self, dt: float) -> None:
        """Move every shape, touching or lifted, by its exact motion over ``dt`` seconds."""
        step = _checks.finite(dt, "dt")
        for shape in self._shapes.values():
            shape.advance(step)

    def displacement(self, name: str, points: ArrayLike, dt: float) -> NDArray[np.float64]:
        """True displacement over the next ``dt`` seconds of points on the named shape.

        Args:
            name: the shape.
            points: metres, world frame, shape (N, 2): where the points are now.
            dt: seconds.

        Returns:
            metres, world frame, shape (N, 2).
        """
        return self[name].displacement(points, dt)

    def point_velocity(self, name: str, points: ArrayLike) -> NDArray[np.float64]:
        """Instantaneous velocity (m/s, world frame, shape (N, 2)) of points on the
        named shape (metres, world frame, shape (N, 2))."""
        return self[name].point_velocity(points)

    def copy(self) -> Hand:
        """An independent copy: shapes, poses, twists and touch flags."""
        twin = Hand()
        twin._shapes = {name: shape.copy() for name, shape in self._shapes.items()}
        twin._touching = dict(self._touching)
        return twin

    def __repr__(self) -> str:
        parts = ", ".join(f"{name}={'down' if down else 'lifted'}" for name, _shape, down in self)
        return f"Hand({parts})"
