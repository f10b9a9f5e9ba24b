"""The finger controller: actions in, a moving hand out.

Actions only ever move the synthetic hand; the hand reaches the physics through the
rendered mask, like a real hand on a real table. Two action modes:

- ``fingers``: per finger ``(vx, vy, touch)`` in [-1, 1]: a planar velocity (scaled
  by ``max_speed``) and a touch flag (down when > 0). Lifted fingers keep moving
  above the table.
- ``grip``: ``(vx, vy, turn, open, touch)`` in [-1, 1]: the grip centre's velocity,
  its turn rate (scaled by ``max_turn_rate``), the rate at which the fingers open or
  close (``max_open_rate``) and one touch flag for all. The fingers sit at equal
  angles around the grip centre, their facing edges ``opening`` apart.

Out-of-range actions are clipped to [-1, 1]; NaN or infinite ones raise
``ValueError``. Fingers never leave the table (their centres are clamped inside it,
a fingertip radius from the edge) and the opening stays within its limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from graspenv.surface.geometry import Surface
from graspenv.surface.hand import Hand
from graspenv.surface.shapes import Fingertip

__all__ = ["ActionMode", "ControllerConfig", "FingerController", "GripState"]

ActionMode = Literal["fingers", "grip"]


@dataclass(frozen=True)
class ControllerConfig:
    """Limits of the synthetic hand.

    Attributes:
        n_fingers: fingertips in the hand.
        finger_radius: fingertip radius, metres.
        max_speed: finger (or grip centre) speed at action 1, m/s.
        max_turn_rate: grip turn rate at action 1, rad/s.
        max_open_rate: grip opening rate at action 1, m/s.
        min_opening: smallest gap between facing fingertip edges, metres.
        max_opening: largest gap, metres.
    """

    n_fingers: int = 2
    finger_radius: float = 0.008
    max_speed: float = 0.2
    max_turn_rate: float = 2.0
    max_open_rate: float = 0.1
    min_opening: float = 0.0
    max_opening: float = 0.16

    def __post_init__(self) -> None:
        if not (isinstance(self.n_fingers, int) and 1 <= self.n_fingers <= 10):
            raise ValueError(f"controller.n_fingers must be 1..10, got {self.n_fingers!r}")
        for key in ("finger_radius", "max_speed", "max_turn_rate", "max_open_rate"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"controller.{key} must be finite and > 0, got {value!r}")
        if not 0 <= self.min_opening < self.max_opening:
            raise ValueError(
                "controller.min_opening must be >= 0 and < max_opening, got "
                f"{self.min_opening!r} and {self.max_opening!r}"
            )


@dataclass
class GripState:
    """Where the grip is: centre (metres, world frame, (2,)), angle of the first
    finger's direction from the centre (radians), opening (metres), touching."""

    centre: NDArray[np.float64]
    angle: float
    opening: float
    touching: bool


def finger_names(n: int) -> tuple[str, ...]:
    """Names of the fingers of an n-finger hand, thumb first."""
    names = ("thumb", "index", "middle", "ring", "little")
    return tuple(names[i] if i < len(names) else f"finger{i}" for i in range(n))


class FingerController:
    """Turns actions into the motion of a synthetic hand of round fingertips.

    Args:
        config: the hand's limits.
        surface: the table (size and frame interval).
        mode: ``fingers`` or ``grip``.
    """

    def __init__(self, config: ControllerConfig, surface: Surface, mode: ActionMode) -> None:
        if mode not in ("fingers", "grip"):
            raise ValueError(f"action_mode must be 'fingers' or 'grip', got {mode!r}")
        self.config = config
        self.surface = surface
        self.mode: ActionMode = mode
        self.names = finger_names(config.n_fingers)
        r = config.finger_radius
        self._limit = 0.5 * np.asarray(surface.size) - r
        self.hand = Hand()
        for name in self.names:
            self.hand.add(name, Fingertip((0.0, 0.0), radii=(r, r)), touching=False)
        self._grip = GripState(np.zeros(2), 0.0, config.max_opening, False)
        self._finger_angles = 2.0 * math.pi * np.arange(config.n_fingers) / config.n_fingers
        # The fingers' places about the grip centre, kept with the grip.
        self._offsets = self._grip_offsets(self._grip)

    @property
    def grip(self) -> GripState:
        """A copy of the grip the fingers sit on (move it with :meth:`place_grip` or
        actions)."""
        grip = self._grip
        return GripState(grip.centre.copy(), grip.angle, grip.opening, grip.touching)

    @property
    def action_size(self) -> int:
        return 3 * self.config.n_fingers if self.mode == "fingers" else 5

    # -- placing -------------------------------------------------------------------------

    def place_grip(self, grip: GripState) -> None:
        """Put the fingers around a grip (any action mode)."""
        cfg = self.config
        self._grip = GripState(
            np.asarray(grip.centre, dtype=float).copy(),
            float(grip.angle),
            float(np.clip(grip.opening, cfg.min_opening, cfg.max_opening)),
            bool(grip.touching),
        )
        self._offsets = self._grip_offsets(self._grip)
        self._pose_from_grip()

    def place_fingers(self, centres: ArrayLike, touching: ArrayLike) -> None:
        """Put each finger at a position (metres, world frame, (n, 2)), up or down."""
        xy = np.asarray(centres, dtype=float).reshape(self.config.n_fingers, 2)
        if not np.all(np.isfinite(xy)):
            raise ValueError(f"finger centres must be finite, got {xy.tolist()}")
        down = np.broadcast_to(np.asarray(touching, dtype=bool), (self.config.n_fingers,))
        xy = np.clip(xy, -self._limit, self._limit)
        for name, position, flag in zip(self.names, xy, down.tolist(), strict=True):
            self.hand[name].set_translation(position, 0.0, np.zeros(2))
            self.hand.set_touching(name, flag)

    def _grip_offsets(self, grip: GripState) -> NDArray[np.float64]:
        reach = 0.5 * grip.opening + self.config.finger_radius
        angles = grip.angle + self._finger_angles
        return reach * np.column_stack([np.cos(angles), np.sin(angles)])

    def _pose_from_grip(self) -> None:
        """The fingers where the grip puts them (its offsets already computed)."""
        self.place_fingers(self._grip.centre + self._offsets, self._grip.touching)

    # -- stepping ------------------------------------------------------------------------

    def apply(self, action: ArrayLike) -> NDArray[np.float32]:
        """Set the hand's motion for the next camera frame from an action.

        Args:
            action: shape (action_size,), values in [-1, 1] (clipped).

        Returns:
            The clipped action.

        Raises:
            ValueError: wrong shape, or a NaN or infinite value.
        """
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (self.action_size,):
            raise ValueError(
                f"action must have shape ({self.action_size},) for action_mode="
                f"{self.mode!r} with {self.config.n_fingers} fingers, got {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {a.tolist()}")
        a = np.clip(a, -1.0, 1.0)
        if self.mode == "fingers":
            self._apply_fingers(a.reshape(-1, 3))
        else:
            self._apply_grip(a)
        return a.astype(np.float32)

    def _apply_fingers(self, a: NDArray[np.float64]) -> None:
        dt = self.surface.dt
        for name, (vx, vy, touch) in zip(self.names, a, strict=True):
            tip = self.hand[name]
            velocity = self.config.max_speed * np.array([vx, vy])
            # Stop at the table's edge: the next centre must stay inside the limit.
            goal = np.clip(tip.centre + velocity * dt, -self._limit, self._limit)
            tip.set_twist((goal - tip.centre) / dt, 0.0)
            self.hand.set_touching(name, bool(touch > 0.0))

    def _apply_grip(self, a: NDArray[np.float64]) -> None:
        cfg, dt, grip = self.config, self.surface.dt, self._grip
        velocity = cfg.max_speed * a[:2]
        goal_centre = np.clip(grip.centre + velocity * dt, -self._limit, self._limit)
        turn = cfg.max_turn_rate * a[2] * dt
        opening = float(
            np.clip(grip.opening + cfg.max_open_rate * a[3] * dt, cfg.min_opening, cfg.max_opening)
        )
        touching = bool(a[4] > 0.0)
        goal = GripState(goal_centre, grip.angle + turn, opening, touching)
        offsets = self._grip_offsets(goal)
        now = grip.centre + self._offsets
        then = goal_centre + offsets
        velocities = (then - now) / dt
        for name, velocity in zip(self.names, velocities, strict=True):
            tip = self.hand[name]
            # Each fingertip moves straight to its place in the next frame; a round
            # tip's own rotation is invisible, so only its centre's path matters.
            tip.set_translation(tip.centre, tip.angle, velocity)
            self.hand.set_touching(name, touching)
        self._grip, self._offsets = goal, offsets

    def advance(self) -> None:
        """Move the hand by one camera frame (after rendering this frame's mask)."""
        if self.mode == "grip":
            # The fingers go exactly where the grip puts them, so rounding never
            # drifts (moving them by their twist first would change nothing).
            self._pose_from_grip()
        else:
            self.hand.advance(self.surface.dt)

    # -- reading -------------------------------------------------------------------------

    def finger_positions(self) -> NDArray[np.float64]:
        """Fingertip centres, metres, world frame, shape (n, 2)."""
        return np.array([self.hand[name].centre for name in self.names], dtype=float)

    def finger_velocities(self) -> NDArray[np.float64]:
        """Fingertip velocities for the coming frame, m/s, world frame, shape (n, 2)."""
        return np.array([self.hand[name].linear_velocity for name in self.names], dtype=float)

    def touching(self) -> NDArray[np.bool_]:
        """Whether each finger is down, shape (n,)."""
        return np.array([self.hand.is_touching(name) for name in self.names], dtype=bool)
