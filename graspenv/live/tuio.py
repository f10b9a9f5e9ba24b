"""TUIO 1.1 over UDP: a tabletop tracker's cursors and blobs become touches.

TUIO (tuio.org, "TUIO 1.1 Protocol Specification") sends OSC bundles, one per
tracker frame and profile, each holding ``source`` (optional, 1.1), ``alive``,
any number of ``set`` and one ``fseq`` message:

- ``/tuio/2Dcur set s x y X Y m``: a cursor, a fingertip of
  :data:`~graspenv.live.touches.DEFAULT_RADIUS`;
- ``/tuio/2Dblb set s x y a w h f X Y A m r``: a blob, an ellipse whose axes are
  ``w`` and ``h`` (its full width and height, normalised like x and y) turned by
  ``a`` radians;
- positions are normalised to [0, 1] with the origin at the top left, as the touches
  of :mod:`graspenv.live.touches` are;
- ``alive s…`` lists the session ids still on the surface: the others lifted;
- ``fseq f`` closes the frame: what the bundle set is applied then. A frame whose
  ``f`` is below the last applied one is late (UDP reorders) and dropped, unless it
  is more than 100 below (the tracker restarted), as the reference client does; ``f``
  of −1 (or 0) marks an unsequenced frame, always applied;
- ``source name@address`` names the tracker; several trackers may touch at once,
  each with its own session ids. Without it, the sender's address names it.

A tracker that falls silent for :data:`SOURCE_TIMEOUT` seconds has its touches
lifted, so that a crashed tracker does not leave fingers on the table.

Everything a datagram holds is checked: bad datagrams (not OSC, wrong argument types,
numbers that are not finite or out of range, more than
:data:`~graspenv.live.touches.MAX_TOUCHES` alive) are dropped and counted, never
raised; UDP has no channel to answer on.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pythonosc.osc_packet import OscPacket

from graspenv.live.touches import MAX_TOUCHES, InputError, Touch, TouchBoard, checked_number

__all__ = ["MAX_DATAGRAM", "SOURCE_TIMEOUT", "TuioReceiver"]

#: Largest datagram read, bytes: 64 blobs' set messages take about 5 kB.
MAX_DATAGRAM = 16384
#: Seconds of silence after which a tracker's touches are lifted.
SOURCE_TIMEOUT = 2.0
#: Frames a late ``fseq`` may lag before it counts as the tracker's restart.
_RESTART_GAP = 100

_PROFILES = {"/tuio/2Dcur": 6, "/tuio/2Dblb": 12}


@dataclass
class _Profile:
    """One tracker's one profile: its alive ids, its touches and its last frame."""

    alive: tuple[int, ...] = ()
    touches: dict[int, Touch] = field(default_factory=dict)
    pending: dict[int, Touch] = field(default_factory=dict)
    pending_alive: tuple[int, ...] | None = None
    frame: int = 0
    seen: float = 0.0


def _int(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(f"{name} must be an int32")
    return value


def _touch(address: str, args: list[Any]) -> tuple[int, Touch]:
    """The session id and touch of one ``set`` message's arguments (after ``set``)."""
    if len(args) != _PROFILES[address]:
        raise InputError(f"{address} set takes {_PROFILES[address]} arguments, got {len(args)}")
    session = _int(args[0], "session id")
    x = checked_number(args[1], "x", 0.0, 1.0)
    y = checked_number(args[2], "y", 0.0, 1.0)
    if address == "/tuio/2Dcur":
        return session, Touch(x, y)
    angle = checked_number(args[3], "angle", -2.0 * math.pi, 2.0 * math.pi)
    width = checked_number(args[4], "width", 0.0, 1.0)
    height = checked_number(args[5], "height", 0.0, 1.0)
    return session, Touch(x, y, rx=0.5 * width or None, ry=0.5 * height or None, angle=angle)


class TuioReceiver:
    """Turns TUIO datagrams into touches on a :class:`TouchBoard`.

    Args:
        board: where the touches go; each tracker's profile is one source,
            ``tuio:<source>:<profile>``.
        clock: seconds, for the silence timeout (tests pass their own).

    Attributes:
        datagrams: datagrams read.
        dropped: datagrams or messages dropped as malformed or out of bounds.
        last_error: why the last one was dropped.
    """

    def __init__(self, board: TouchBoard, clock: Callable[[], float] = time.monotonic) -> None:
        self.board = board
        self._clock = clock
        self._profiles: dict[tuple[str, str], _Profile] = {}
        self.datagrams = 0
        self.dropped = 0
        self.last_error = ""

    def feed(self, data: bytes, sender: str) -> None:
        """Handle one datagram from ``sender`` (``host:port``); never raises."""
        self.datagrams += 1
        try:
            if len(data) > MAX_DATAGRAM:
                raise InputError(f"datagram of {len(data)} bytes (at most {MAX_DATAGRAM})")
            messages = [timed.message for timed in OscPacket(data).messages]
        except Exception as err:
            self._drop(f"not an OSC packet: {err}")
            return
        source = sender
        for message in messages:
            try:
                source = self._message(message.address, list(message.params), source, sender)
            except InputError as err:
                self._drop(f"{message.address}: {err}")

    def expire(self) -> None:
        """Lift the touches of trackers silent for :data:`SOURCE_TIMEOUT` seconds."""
        now = self._clock()
        for key, profile in list(self._profiles.items()):
            if now - profile.seen > SOURCE_TIMEOUT:
                del self._profiles[key]
                self.board.drop(self._source_name(key))

    def _drop(self, reason: str) -> None:
        self.dropped += 1
        self.last_error = reason

    @staticmethod
    def _source_name(key: tuple[str, str]) -> str:
        return f"tuio:{key[0]}:{key[1]}"

    def _message(self, address: str, args: list[Any], source: str, sender: str) -> str:
        if address not in _PROFILES:
            return source  # other profiles (2Dobj, 25D, 3D) carry no touch here
        if not args or not isinstance(args[0], str):
            raise InputError("the first argument must be a command string")
        command, rest = args[0], args[1:]
        if command == "source":
            if len(rest) != 1 or not isinstance(rest[0], str) or len(rest[0]) > 128:
                raise InputError("source takes one name of at most 128 characters")
            return f"{rest[0]}|{sender}"
        key = (source, address.rsplit("/", 1)[1])
        profile = self._profiles.get(key)
        if profile is None:
            if len(self._profiles) >= 16:
                raise InputError("at most 16 tracker profiles at once")
            profile = self._profiles[key] = _Profile()
        profile.seen = self._clock()
        if command == "set":
            session, touch = _touch(address, rest)
            if len(profile.pending) >= MAX_TOUCHES:
                raise InputError(f"more than {MAX_TOUCHES} set messages in a frame")
            profile.pending[session] = touch
        elif command == "alive":
            if len(rest) > MAX_TOUCHES:
                raise InputError(f"at most {MAX_TOUCHES} alive ids, got {len(rest)}")
            profile.pending_alive = tuple(_int(a, "alive id") for a in rest)
        elif command == "fseq":
            if len(rest) != 1:
                raise InputError("fseq takes one frame number")
            self._frame(key, profile, _int(rest[0], "fseq"))
        else:
            raise InputError(f"unknown command {command!r}")
        return source

    def _frame(self, key: tuple[str, str], profile: _Profile, frame: int) -> None:
        late = 0 < frame < profile.frame and profile.frame - frame <= _RESTART_GAP
        pending, alive = profile.pending, profile.pending_alive
        profile.pending, profile.pending_alive = {}, None
        if late:
            return
        if frame > 0:
            profile.frame = frame
        if alive is not None:
            profile.alive = alive
        touches = {**profile.touches, **pending}
        profile.touches = {s: touches[s] for s in profile.alive if s in touches}
        self.board.put(self._source_name(key), list(profile.touches.values()))
