"""The live table's web server (aiohttp): the page, its WebSocket, the state, and
TUIO over UDP.

Routes (nothing else is served; static files come from this package only, by fixed
names, never from a path a client names):

- ``GET /``: the page (``static/index.html``), ``GET /app.js``: its script;
- ``GET /state``: the table's :class:`~graspenv.live.table.LiveState` as JSON;
- ``POST /reset``: the scene back at its start;
- ``GET /ws``: the page's WebSocket. The page sends
  ``{"type": "touches", "touches": [{"x", "y", "rx", "ry", "angle"}, …]}`` (see
  :func:`graspenv.live.touches.parse_touches`) or ``{"type": "reset"}``; the server
  sends ``{"type": "view", …}`` at :data:`VIEW_HZ` and ``{"type": "error",
  "message": …}`` for a message it dropped.

Safe defaults: the server binds to loopback (``--host 0.0.0.0`` exposes the table,
and anyone who can reach the port can touch it); a WebSocket upgrade whose
``Origin`` is not this server's host is refused, and so is such a ``POST /reset``
(a page elsewhere cannot drive the table through a visitor's browser); at most
:data:`MAX_CONNECTIONS` pages at once; messages of at most :data:`MAX_MESSAGE`
bytes; at most :data:`MAX_RATE` messages a second from a page (more are dropped
with an error) and :data:`MAX_DATAGRAM_RATE` datagrams a second on the TUIO port.
Bad input is answered with an error where there is a channel and dropped; it never
stops the server or touches another client.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import signal
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

from graspenv.live.table import LiveTable
from graspenv.live.touches import InputError, parse_touches
from graspenv.live.tuio import TuioReceiver

__all__ = [
    "MAX_CONNECTIONS",
    "MAX_DATAGRAM_RATE",
    "MAX_MESSAGE",
    "MAX_RATE",
    "VIEW_HZ",
    "LiveServer",
    "serve",
    "serving_in_thread",
]

#: Pages connected at once.
MAX_CONNECTIONS = 16
#: Bytes in one WebSocket message (64 touches take about 5 kB) or request body.
MAX_MESSAGE = 16384
#: Messages a second one page may send (a touchscreen sends at most about 120).
MAX_RATE = 240.0
#: Datagrams a second the TUIO port reads (trackers send 30–200).
MAX_DATAGRAM_RATE = 2000.0
#: Views a second sent to each page.
VIEW_HZ = 30.0

_STATIC = {"/": ("index.html", "text/html"), "/app.js": ("app.js", "text/javascript")}


class _Bucket:
    """A token bucket: ``rate`` events a second, bursts of one second's worth."""

    def __init__(self, rate: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.rate, self._clock = rate, clock
        self._tokens, self._last = rate, clock()

    def take(self) -> bool:
        now = self._clock()
        self._tokens = min(self.rate, self._tokens + (now - self._last) * self.rate)
        self._last = now
        if self._tokens < 1.0:
            return False
        self._tokens -= 1.0
        return True


class _TuioProtocol(asyncio.DatagramProtocol):
    def __init__(self, receiver: TuioReceiver, table: LiveTable) -> None:
        self.receiver, self.table = receiver, table
        self._bucket = _Bucket(MAX_DATAGRAM_RATE)

    def datagram_received(self, data: bytes, addr: tuple[Any, ...]) -> None:
        if not self._bucket.take():
            self.receiver.dropped += 1
            self.receiver.last_error = "rate limit"
            return
        self.receiver.feed(data, f"{addr[0]}:{addr[1]}")
        self.table.touched()


@dataclass
class _Client:
    socket: web.WebSocketResponse
    source: str
    bucket: _Bucket
    sending: asyncio.Task[None] | None = None


class LiveServer:
    """The server of one :class:`LiveTable`: every page and TUIO source touches it.

    Args:
        table: the table (started and stopped with the server).
        host, port: where to listen (port 0: any free one, see :attr:`port`).
        tuio_port: the UDP port for TUIO, on the same host, or ``None``.
    """

    def __init__(
        self,
        table: LiveTable,
        host: str = "127.0.0.1",
        port: int = 8000,
        tuio_port: int | None = None,
    ) -> None:
        self.table, self.host, self.port, self.tuio_port = table, host, port, tuio_port
        self.tuio = TuioReceiver(table.board)
        self._clients: dict[int, _Client] = {}
        self._ids = itertools.count()
        self._runner: web.AppRunner | None = None
        self._transport: asyncio.DatagramTransport | None = None
        self._tasks: list[asyncio.Task[None]] = []
        self.app = web.Application(client_max_size=MAX_MESSAGE)
        self.app.add_routes(
            [
                web.get("/", self._static),
                web.get("/app.js", self._static),
                web.get("/state", self._state),
                web.post("/reset", self._reset),
                web.get("/ws", self._socket),
            ]
        )

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    async def start(self) -> None:
        """Listen, start the table's loop and the senders."""
        self._runner = web.AppRunner(self.app, access_log=None, handle_signals=False)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.host, self.port)
        await site.start()
        if self.port == 0:
            self.port = int(self._runner.addresses[0][1])
        if self.tuio_port is not None:
            loop = asyncio.get_running_loop()
            transport, _ = await loop.create_datagram_endpoint(
                lambda: _TuioProtocol(self.tuio, self.table), local_addr=(self.host, self.tuio_port)
            )
            self._transport = transport
            if self.tuio_port == 0:
                self.tuio_port = transport.get_extra_info("sockname")[1]
        self.table.start()
        self._tasks = [asyncio.create_task(self._broadcast()), asyncio.create_task(self._expire())]

    async def stop(self) -> None:
        """Close every page, stop listening and stop the table."""
        for task in self._tasks:
            task.cancel()
        for client in list(self._clients.values()):
            with contextlib.suppress(Exception):
                await client.socket.close()
        if self._transport is not None:
            self._transport.close()
        if self._runner is not None:
            await self._runner.cleanup()
        self.table.stop()

    # -- HTTP --------------------------------------------------------------------------

    async def _static(self, request: web.Request) -> web.Response:
        name, kind = _STATIC[request.path]
        text = resources.files("graspenv.live").joinpath("static", name).read_text("utf-8")
        return web.Response(text=text, content_type=kind, headers={"Cache-Control": "no-cache"})

    async def _state(self, request: web.Request) -> web.Response:
        body = self.table.state().json()
        body["tuio"] = {"datagrams": self.tuio.datagrams, "dropped": self.tuio.dropped}
        body["pages"] = len(self._clients)
        return web.json_response(body)

    async def _reset(self, request: web.Request) -> web.Response:
        # A page elsewhere could POST a form here through a visitor's browser.
        if not self._same_origin(request):
            raise web.HTTPForbidden(text="the request's origin is not this server")
        self.table.reset()
        return web.json_response({"ok": True})

    # -- the page's socket -------------------------------------------------------------

    def _same_origin(self, request: web.Request) -> bool:
        origin = request.headers.get("Origin")
        if origin is None:  # not a browser: nothing to forge
            return True
        parts = urlsplit(origin)
        return parts.scheme in ("http", "https") and parts.netloc == request.host

    async def _socket(self, request: web.Request) -> web.StreamResponse:
        if not self._same_origin(request):
            raise web.HTTPForbidden(text="the page's origin is not this server")
        if len(self._clients) >= MAX_CONNECTIONS:
            raise web.HTTPServiceUnavailable(text=f"at most {MAX_CONNECTIONS} pages at once")
        socket = web.WebSocketResponse(max_msg_size=MAX_MESSAGE, heartbeat=20.0)
        await socket.prepare(request)
        key = next(self._ids)
        client = _Client(socket, f"page:{key}", _Bucket(MAX_RATE))
        self._clients[key] = client
        try:
            async for message in socket:
                if message.type == WSMsgType.TEXT:
                    await self._message(client, message.data)
                elif message.type == WSMsgType.BINARY:
                    await self._error(client, "send JSON text, not binary")
                else:
                    break
        finally:
            self._clients.pop(key, None)
            self.table.board.drop(client.source)
        return socket

    async def _error(self, client: _Client, text: str) -> None:
        with contextlib.suppress(Exception):
            await client.socket.send_json({"type": "error", "message": text})

    async def _message(self, client: _Client, data: str) -> None:
        if not client.bucket.take():
            await self._error(client, f"more than {MAX_RATE:.0f} messages a second: dropped")
            return
        try:
            message = json.loads(data)
            if not isinstance(message, dict):
                raise InputError("a message must be a JSON object")
            kind = message.get("type")
            if kind == "touches":
                self.table.board.put(client.source, parse_touches(message.get("touches")))
                self.table.touched()
            elif kind == "reset":
                self.table.reset()
            else:
                raise InputError(f"unknown message type {kind!r}")
        except (ValueError, RecursionError) as err:  # JSONDecodeError and InputError
            await self._error(client, str(err))

    # -- background --------------------------------------------------------------------

    async def _broadcast(self) -> None:
        while True:
            await asyncio.sleep(1.0 / VIEW_HZ)
            if not self._clients:
                continue
            view = self.table.view()
            if not view:  # the table draws one from its next frame on
                continue
            text = json.dumps(view)
            for client in list(self._clients.values()):
                # A page still busy with the last view skips this one: views are
                # dropped, never queued.
                if client.sending is None or client.sending.done():
                    client.sending = asyncio.create_task(self._send(client, text))

    @staticmethod
    async def _send(client: _Client, text: str) -> None:
        with contextlib.suppress(Exception):
            await client.socket.send_str(text)

    async def _expire(self) -> None:
        while True:
            await asyncio.sleep(0.5)
            self.tuio.expire()


@contextlib.contextmanager
def serving_in_thread(
    table: LiveTable, host: str = "127.0.0.1", port: int = 0, tuio_port: int | None = None
) -> Iterator[LiveServer]:
    """A started server whose event loop runs in a thread of its own, stopped on exit:
    for tests, measurements and programs that embed the table. Ports 0 pick free
    ones (read them from the server)."""
    loop = asyncio.new_event_loop()
    server = LiveServer(table, host, port, tuio_port)
    ready = threading.Event()
    failed: list[BaseException] = []

    def run() -> None:
        asyncio.set_event_loop(loop)
        try:
            loop.run_until_complete(server.start())
        except BaseException as err:
            failed.append(err)
            ready.set()
            return
        ready.set()
        loop.run_forever()

    thread = threading.Thread(target=run, name="graspenv-server", daemon=True)
    thread.start()
    if not ready.wait(60.0):
        raise TimeoutError("the server did not start within 60 s")
    if failed:
        thread.join(timeout=5.0)
        loop.close()
        raise failed[0]
    try:
        yield server
    finally:
        asyncio.run_coroutine_threadsafe(server.stop(), loop).result(timeout=10.0)
        loop.call_soon_threadsafe(loop.stop)
        thread.join(timeout=10.0)
        loop.close()


def serve(
    table: LiveTable,
    host: str = "127.0.0.1",
    port: int = 8000,
    tuio_port: int | None = None,
    announce: Callable[[str], None] = print,
) -> None:
    """Serve ``table`` until Ctrl-C (``graspenv serve``)."""

    async def run() -> None:
        server = LiveServer(table, host, port, tuio_port)
        await server.start()
        announce(f"serving the table at {server.url} (Ctrl-C stops)")
        if tuio_port is not None:
            announce(f"TUIO 1.1 on udp://{host}:{server.tuio_port}")
        if host not in ("127.0.0.1", "localhost", "::1"):
            announce(f"warning: listening on {host}: anyone who can reach it can touch the table")
        stopping = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stopping.set)
        try:
            await stopping.wait()
        finally:
            await server.stop()
        announce("stopped")

    asyncio.run(run())
