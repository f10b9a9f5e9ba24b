"""Touches on the live table: ellipses in the table's normalised coordinates.

A touch is given the way browsers and TUIO give it: its centre ``(x, y)`` in
``[0, 1]²`` with the origin at the top left of the table (the contact mask's
orientation: ``x`` grows towards +x in the world, ``y`` towards −y), its semi-axes
``rx`` and ``ry`` as fractions of the table's width and height, and ``angle``, the
ellipse's rotation in radians, clockwise as seen on the screen (the direction a
browser's ``rotationAngle`` and TUIO's blob angle turn, with y pointing down). A touch
without radii is a fingertip of :data:`DEFAULT_RADIUS`.

Every source (a page, a TUIO tracker) owns its touches on one shared
:class:`TouchBoard`; the table reads the union of them every frame.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from graspenv.surface.fingertip import Fingertip
from graspenv.surface.geometry import Surface

__all__ = [
    "DEFAULT_RADIUS",
    "MAX_RADIUS",
    "MAX_SOURCES",
    "MAX_TOUCHES",
    "InputError",
    "Touch",
    "TouchBoard",
    "checked_number",
    "parse_touches",
]

#: Radius of a touch that reports none (a mouse, a TUIO cursor), metres.
DEFAULT_RADIUS = 0.008
#: Largest semi-axis a touch may have, metres: a flat palm is about 5 cm across.
MAX_RADIUS = 0.05
#: Touches one message (or one source) may hold.
MAX_TOUCHES = 64
#: Sources (pages and TUIO trackers) touching at once.
MAX_SOURCES = 32


class InputError(ValueError):
    """A message from a client or a tracker that is malformed or out of bounds."""


@dataclass(frozen=True)
class Touch:
    """One touch, in the table's normalised coordinates (the module docstring).

    Attributes:
        x, y: centre, in [0, 1], origin at the table's top left.
        rx, ry: semi-axes along the screen's x and y before the rotation, as
            fractions of the table's width and height; ``None``: a fingertip of
            :data:`DEFAULT_RADIUS`.
        angle: radians, clockwise on the screen.
    """

    x: float
    y: float
    rx: float | None = None
    ry: float | None = None
    angle: float = 0.0

    def shape(self, surface: Surface) -> Fingertip:
        """The fingertip this touch presses on ``surface``: its centre and semi-axes in
        metres, clamped to [half a pixel, :data:`MAX_RADIUS`]."""
        width, height = surface.size
        columns, rows = surface.resolution
        centre = surface.pixel_to_world((self.x * columns - 0.5, self.y * rows - 0.5))
        smallest = 0.5 * float(max(surface.pixel_size))
        ax = DEFAULT_RADIUS if self.rx is None else self.rx * width
        ay = DEFAULT_RADIUS if self.ry is None else self.ry * height
        radii = (min(max(ax, smallest), MAX_RADIUS), min(max(ay, smallest), MAX_RADIUS))
        # The screen shows the table from above, so a turn that looks clockwise on
        # it is clockwise in the world too: a negative angle about +z.
        return Fingertip(centre, angle=-self.angle, radii=radii)


def checked_number(value: Any, name: str, low: float, high: float) -> float:
    """``value`` as a float, if it is a finite number (not a bool) in [low, high].

    Raises:
        InputError: naming ``name``.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{name} must be a number, got {type(value).__name__}")
    number = float(value)
    if not math.isfinite(number) or not low <= number <= high:
        raise InputError(f"{name} must be a finite number in [{low}, {high}], got {value!r}")
    return number


def _radius(value: Any, name: str) -> float | None:
    if value is None:
        return None
    radius = checked_number(value, name, 0.0, 1.0)
    return radius if radius > 0.0 else None


def parse_touches(items: Any) -> list[Touch]:
    """Touches from a page's message: a list of ``{"x", "y"[, "rx", "ry", "angle"]}``.

    Raises:
        InputError: not a list of objects, more than :data:`MAX_TOUCHES`, or a value
            that is not a finite number in range (x, y in [0, 1]; rx, ry in [0, 1],
            0 or null for "not reported"; angle in [−2π, 2π]).
    """
    if not isinstance(items, list):
        raise InputError("touches must be a list")
    if len(items) > MAX_TOUCHES:
        raise InputError(f"at most {MAX_TOUCHES} touches per message, got {len(items)}")
    touches = []
    for i, item in enumerate(items):
        if not isinstance(item, Mapping):
            raise InputError(f"touch {i} must be an object")
        touches.append(
            Touch(
                x=checked_number(item.get("x"), f"touch {i}: x", 0.0, 1.0),
                y=checked_number(item.get("y"), f"touch {i}: y", 0.0, 1.0),
                rx=_radius(item.get("rx"), f"touch {i}: rx"),
                ry=_radius(item.get("ry"), f"touch {i}: ry"),
                angle=checked_number(item.get("angle", 0.0), f"touch {i}: angle", -7.0, 7.0),
            )
        )
    return touches


class TouchBoard:
    """The touches of every source, shared between the server and the table's loop.

    Thread-safe: sources write from the server's event loop, the table reads from its
    own thread.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._touches: dict[str, tuple[Touch, ...]] = {}

    def put(self, source: str, touches: Sequence[Touch]) -> None:
        """Replace ``source``'s touches (an empty sequence lifts them all).

        Raises:
            InputError: more than :data:`MAX_TOUCHES`, or a new source beyond
                :data:`MAX_SOURCES`.
        """
        if len(touches) > MAX_TOUCHES:
            raise InputError(f"at most {MAX_TOUCHES} touches per source, got {len(touches)}")
        with self._lock:
            if not touches:
                self._touches.pop(source, None)
                return
            if source not in self._touches and len(self._touches) >= MAX_SOURCES:
                raise InputError(f"at most {MAX_SOURCES} sources touch at once")
            self._touches[source] = tuple(touches)

    def drop(self, source: str) -> None:
        """Lift all of ``source``'s touches (it disconnected or went silent)."""
        with self._lock:
            self._touches.pop(source, None)

    def clear(self) -> None:
        with self._lock:
            self._touches.clear()

    def touches(self) -> list[Touch]:
        """Every source's touches, in the order the sources first touched."""
        with self._lock:
            return [t for group in self._touches.values() for t in group]

    @property
    def sources(self) -> int:
        with self._lock:
            return len(self._touches)
