"""The server under bad input: garbage on the HTTP port, malformed, oversized and
out-of-range messages, too many touches, a foreign origin, too many pages, random
datagrams on the TUIO port. After each, ``GET /state`` still answers and the other
pages are unaffected. Everything binds to loopback and every wait is bounded."""

from __future__ import annotations

import asyncio
import contextlib
import json
import random
import socket
import time
from typing import Any

import aiohttp
import numpy as np
import pytest

from graspenv.config import load_config
from graspenv.live.server import MAX_CONNECTIONS, MAX_MESSAGE, MAX_RATE
from graspenv.live.table import LiveTable
from tests.live._helpers import Running, running, tuio_cursor_bundle

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.fixture(scope="module")
def live() -> Any:
    with running() as server:
        yield server


def _ws_url(live: Running) -> str:
    return live.url.replace("http://", "ws://") + "ws"


async def _exchange(
    live: Running, payloads: list[str | bytes], replies: int, **kw: Any
) -> list[Any]:
    """Send ``payloads`` on one socket and return the first ``replies`` error or close
    messages (views are skipped), within 10 s."""
    got: list[Any] = []
    async with (
        aiohttp.ClientSession() as session,
        session.ws_connect(_ws_url(live), **kw) as ws,
    ):
        for p in payloads:
            await (ws.send_bytes(p) if isinstance(p, bytes) else ws.send_str(p))
        deadline = time.monotonic() + 10.0
        while len(got) < replies and time.monotonic() < deadline:
            msg = await ws.receive(timeout=max(0.1, deadline - time.monotonic()))
            if msg.type == aiohttp.WSMsgType.TEXT:
                data = json.loads(msg.data)
                if data["type"] == "error":
                    got.append(data["message"])
            else:
                got.append(msg.type)
                break
    return got


def test_state_and_reset_answer(live: Running) -> None:
    state = live.state()
    assert set(state) >= {"frame", "objects", "contacts"}
    box = state["objects"]["box"]
    assert len(box["position"]) == 3 and len(box["quaternion"]) == 4
    assert abs(box["position"][2] - 0.015) < 0.002  # the 3 cm box resting on the table
    assert live.post("reset") == {"ok": True}
    live.wait_frames(2)


def test_the_page_and_its_script_are_served_and_nothing_else(live: Running) -> None:
    import urllib.error
    import urllib.request

    page = urllib.request.urlopen(live.url, timeout=5).read().decode()
    assert '<canvas id="table"' in page and "touch-action: none" in page
    assert urllib.request.urlopen(live.url + "app.js", timeout=5).status == 200
    for path in ("static/index.html", "..%2f..%2fetc%2fpasswd", "app.js/../../x", "graspenv"):
        with pytest.raises(urllib.error.HTTPError) as err:
            urllib.request.urlopen(live.url + path, timeout=5)
        assert err.value.code == 404


def test_garbage_bytes_on_the_http_port(live: Running) -> None:
    rng = random.Random(1)
    for size in (1, 100, 5000, 70000):
        with socket.create_connection((live.server.host, live.server.port), timeout=5) as s:
            s.sendall(bytes(rng.randrange(256) for _ in range(size)))
            s.settimeout(5)
            with contextlib.suppress(TimeoutError, ConnectionResetError):
                s.recv(1024)
    assert live.state()["frame"] >= 0


@pytest.mark.parametrize(
    "payload, words",
    [
        ("{not json", "Expecting"),
        ("[1, 2]", "JSON object"),
        ('{"type": "dance"}', "unknown message type"),
        ('{"type": "touches", "touches": [{"x": NaN, "y": 0.5}]}', "finite"),
        ('{"type": "touches", "touches": [{"x": 2, "y": 0.5}]}', "in [0.0, 1.0]"),
        ('{"type": "touches", "touches": 5}', "must be a list"),
        (json.dumps({"type": "touches", "touches": [{"x": 0.5, "y": 0.5}] * 65}), "at most 64"),
        ("[" * 5000 + "]" * 5000, "recursion"),
    ],
)
def test_bad_messages_get_an_error_and_are_dropped(live: Running, payload: str, words: str) -> None:
    (reply,) = asyncio.run(_exchange(live, [payload], 1))
    assert isinstance(reply, str) and words in reply, reply
    state = live.state()
    assert state["touches"] == 0  # nothing of it reached the table


def test_binary_and_oversized_messages(live: Running) -> None:
    (reply,) = asyncio.run(_exchange(live, [b"\x00\x01"], 1))
    assert "not binary" in reply
    big = json.dumps({"type": "touches", "touches": [], "pad": "x" * (2 * MAX_MESSAGE)})
    (reply,) = asyncio.run(_exchange(live, [big], 1))
    assert reply in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.CLOSING)
    assert live.state()["pages"] == 0 or live.state()["frame"] >= 0


def test_a_flood_is_cut_at_the_rate_limit(live: Running) -> None:
    touch = json.dumps({"type": "touches", "touches": [{"x": 0.9, "y": 0.9}]})
    n = int(2.5 * MAX_RATE)
    errors = asyncio.run(_exchange(live, [touch] * n, 1))
    assert errors and "messages a second" in errors[0]
    live.wait_frames(3)  # the page's touches were lifted when it left
    assert live.state()["touches"] == 0


def test_a_foreign_origin_is_refused(live: Running) -> None:
    async def attempt(origin: str) -> int:
        async with aiohttp.ClientSession() as session:
            try:
                async with session.ws_connect(_ws_url(live), headers={"Origin": origin}):
                    return 101
            except aiohttp.WSServerHandshakeError as err:
                return err.status

    assert asyncio.run(attempt("http://evil.example")) == 403
    assert asyncio.run(attempt(f"http://127.0.0.1:{live.server.port}")) == 101


def test_a_foreign_page_cannot_reset_the_table(live: Running) -> None:
    import urllib.error
    import urllib.request

    request = urllib.request.Request(
        live.url + "reset", data=b"", method="POST", headers={"Origin": "http://evil.example"}
    )
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(request, timeout=5)
    assert err.value.code == 403


def test_too_many_pages(live: Running) -> None:
    async def crowd() -> tuple[int, list[int]]:
        async with aiohttp.ClientSession() as session:
            sockets = [await session.ws_connect(_ws_url(live)) for _ in range(MAX_CONNECTIONS)]
            try:
                await session.ws_connect(_ws_url(live))
                refused = 101
            except aiohttp.WSServerHandshakeError as err:
                refused = err.status
            # The others still work: one touches, and is seen.
            await sockets[0].send_json({"type": "touches", "touches": [{"x": 0.9, "y": 0.9}]})
            await asyncio.sleep(0.3)
            touches = [live.state()["touches"]]
            for ws in sockets:
                await ws.close()
            return refused, touches

    refused, touches = asyncio.run(crowd())
    assert refused == 503 and touches == [1]


def test_random_datagrams_on_the_tuio_port(live: Running) -> None:
    rng = np.random.default_rng(2)
    port = live.server.tuio_port
    assert port
    before = live.state()["tuio"]
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
        for _ in range(300):
            udp.sendto(rng.bytes(int(rng.integers(1, 1400))), ("127.0.0.1", port))
            time.sleep(0.001)  # paced: loopback drops what overflows the socket buffer
        udp.sendto(tuio_cursor_bundle(1, {1: (0.875, 0.875)}), ("127.0.0.1", port))
    # The receiver still works after the garbage: the cursor reaches the table.
    deadline = time.monotonic() + 5
    while live.state()["touches"] != 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    after = live.state()["tuio"]
    assert live.state()["touches"] == 1
    read = after["datagrams"] - before["datagrams"]
    assert read >= 200 and after["dropped"] - before["dropped"] == read - 1
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
        udp.sendto(tuio_cursor_bundle(2, {}), ("127.0.0.1", port))
    live.wait_frames(3)


def test_an_environment_task_is_served_with_its_goal_and_success() -> None:
    import gymnasium as gym

    env = gym.make("graspenv/TurnInPlace-v0").unwrapped
    table = LiveTable(env, seed=3)
    assert table.view() == {}  # asked for: drawn from the next frame on
    state = table.step_once()
    view = table.view()
    assert state.success is False and view["task"] == "TurnInPlace"
    assert view["goal"] and len(view["goal"]["outline"]) == 4
    table.stop()


def test_record_writes_masks_that_replay_plays(tmp_path: Any) -> None:
    from graspenv.live.touches import Touch
    from graspenv.replay import replay

    table = LiveTable(load_config(None), record=tmp_path / "rec")
    table.board.put("t", [Touch(0.5, 0.5)])
    for _ in range(6):
        table.step_once()
    table.stop()
    pngs = sorted((tmp_path / "rec").glob("*.png"))
    assert len(pngs) == 6 and (tmp_path / "rec" / "scene.json").exists()
    result = replay(tmp_path / "rec", out=tmp_path / "out", video="gif")
    assert result.frames == 6
