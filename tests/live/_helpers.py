"""A live server on loopback in a thread of its own, and TUIO and touch gestures."""

from __future__ import annotations

import json
import math
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from graspenv.config import load_config
from graspenv.live.server import LiveServer, serving_in_thread
from graspenv.live.table import LiveTable

#: The default scene's table, metres.
TABLE = (0.61, 0.46)


class Running:
    """A started :class:`LiveServer`, and what the tests ask of it."""

    def __init__(self, server: LiveServer) -> None:
        self.server = server

    @property
    def url(self) -> str:
        return self.server.url

    def state(self, timeout: float = 5.0) -> dict[str, Any]:
        with urllib.request.urlopen(self.url + "state", timeout=timeout) as reply:
            result: dict[str, Any] = json.load(reply)
            return result

    def post(self, path: str) -> dict[str, Any]:
        request = urllib.request.Request(self.url + path, data=b"", method="POST")
        with urllib.request.urlopen(request, timeout=5.0) as reply:
            result: dict[str, Any] = json.load(reply)
            return result

    def wait_frames(self, frames: int, timeout: float = 10.0) -> dict[str, Any]:
        start = self.state()["frame"]
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            state = self.state()
            if state["frame"] >= start + frames:
                return state
            time.sleep(0.02)
        raise TimeoutError(f"{frames} frames did not pass in {timeout} s")


@contextmanager
def running(table: LiveTable | None = None, tuio: bool = True) -> Iterator[Running]:
    """A server on 127.0.0.1, any free ports, stopped on exit (bounded waits)."""
    table = table or LiveTable(load_config(None))
    with serving_in_thread(table, "127.0.0.1", 0, 0 if tuio else None) as server:
        yield Running(server)


def to_normalised(x: float, y: float) -> tuple[float, float]:
    """World metres to the table's normalised coordinates (origin top left)."""
    return (x + TABLE[0] / 2) / TABLE[0], (TABLE[1] / 2 - y) / TABLE[1]


def pinch_and_turn(
    start_radius: float = 0.040,
    squeeze_radius: float = 0.035,
    turn: float = math.pi / 2,
    rate: float = 60.0,
) -> list[list[tuple[float, float]]]:
    """Two fingertips either side of the default box (at the table's centre): down,
    squeeze over 1/3 s, turn by ``turn`` over 1.5 s, hold 1/3 s; one list of
    normalised positions per event, ``rate`` events a second."""

    def pair(radius: float, angle: float) -> list[tuple[float, float]]:
        return [
            to_normalised(radius * math.cos(angle + s), radius * math.sin(angle + s))
            for s in (0.0, math.pi)
        ]

    squeeze, turning, hold = round(rate / 3), round(1.5 * rate), round(rate / 3)
    events = [pair(start_radius, 0.0)] * round(rate / 10)
    events += [
        pair(start_radius + (squeeze_radius - start_radius) * (k + 1) / squeeze, 0.0)
        for k in range(squeeze)
    ]
    events += [pair(squeeze_radius, turn * (k + 1) / turning) for k in range(turning)]
    events += [pair(squeeze_radius, turn)] * hold
    return events


def tuio_cursor_bundle(
    frame: int, cursors: dict[int, tuple[float, float]], source: str | None = None
) -> bytes:
    """A TUIO 1.1 /tuio/2Dcur bundle: [source], alive, set…, fseq."""
    bundle = OscBundleBuilder(IMMEDIATELY)

    def message(*args: Any) -> None:
        m = OscMessageBuilder("/tuio/2Dcur")
        for a in args:
            m.add_arg(a)
        bundle.add_content(m.build())

    if source is not None:
        message("source", source)
    message("alive", *cursors)
    for session, (x, y) in cursors.items():
        message("set", session, float(x), float(y), 0.0, 0.0, 0.0)
    message("fseq", frame)
    return bundle.build().dgram


def yaw_degrees(state: dict[str, Any], name: str = "box") -> float:
    x, y, z, w = state["objects"][name]["quaternion"]
    return math.degrees(math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))
