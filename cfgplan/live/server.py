"""The live page's web server: aiohttp on a thread beside the society.

Read-only by construction: the routes answer ``GET`` (and ``HEAD``) only,
take no parameters, and read the :class:`~cfgplan.live.watch.Watch`;
nothing a browser sends reaches the society. What a client can cost is
bounded (:class:`LiveOptions`): a few streams at once, each a message at
most every :attr:`~LiveOptions.state_every` seconds (a new timeline entry at
once), a stream that cannot be written to for
:attr:`~LiveOptions.write_timeout` seconds dropped. The streams are shared:
when all are taken, a new client takes the place of the one that reads least
(what waits unread in its connection), else of the oldest, whose page
connects again a second later — so clients that hold streams without
reading them cannot keep the operator's page out.

Updates are server-sent events (``GET /events``): one JSON message
``{"state": ..., "entries": [...]}``, the page's state and the timeline
entries the client has not had. The page (``static/``: one HTML file, one
script, one style sheet, no build step, nothing from elsewhere) fetches the
drawing (``GET /drawing.svg``) when its number changes. Every answer forbids
scripts and styles from elsewhere (Content-Security-Policy); a page served
on the loopback answers only requests addressed to a loopback name, so a
web site the browser visits cannot read it through a DNS name of its own
(DNS rebinding).
"""

from __future__ import annotations

import array
import asyncio
import contextlib
import fcntl
import ipaddress
import json
import logging
import socket
import termios
import threading
from dataclasses import dataclass
from functools import partial
from importlib import resources
from typing import Any

from aiohttp import web

from cfgplan.live.address import Address
from cfgplan.live.watch import Watch

__all__ = ["LiveOptions", "LiveServer"]

STATIC = {
    "index.html": "text/html; charset=utf-8",
    "page.js": "text/javascript; charset=utf-8",
    "page.css": "text/css; charset=utf-8",
}
"""The page's files (``cfgplan/live/static``), the only ones served."""

HEADERS = {
    "Content-Security-Policy": (
        "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
        "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"
    ),
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}
LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1", "[::1]"})


@dataclass(frozen=True)
class LiveOptions:
    """What the live page's server allows itself and its clients."""

    clients: int = 8
    """Event streams open at once. One more takes the place of the stream
    whose client reads least (the most of what was written to it still
    waiting to be read), else of the oldest: a few clients that never read,
    or that only hold their streams, cannot lock the operator out."""
    poll: float = 0.05
    """Seconds between two looks at the run (a switch reaches the page within this)."""
    state_every: float = 0.25
    """Seconds between two state messages at most (cycles, ages, freshness)."""
    heartbeat: float = 10.0
    """Seconds of silence after which a stream gets a comment (proxies keep it open)."""
    write_timeout: float = 5.0
    """Seconds a stream may take to accept a message before it is dropped."""
    stop_timeout: float = 2.0
    """Seconds the server may take to stop when the run ends."""
    start_timeout: float = 10.0
    """Seconds the server may take to start serving."""


def _loopback(host: str) -> bool:
    """Whether ``host`` (from a Host header) names this machine: ``localhost``
    or a loopback address, not a name that merely starts like one
    (``127.evil.example`` may be rebound to anything)."""
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _hostname(header: str) -> str:
    """``127.0.0.1:8080`` -> ``127.0.0.1``; ``[::1]:8080`` -> ``::1``."""
    if header.startswith("["):
        return header[1 : header.find("]")] if "]" in header else header
    return header.rpartition(":")[0] if ":" in header else header


def _unread(transport: asyncio.BaseTransport) -> int:
    """Bytes written to a stream's client that it has not read yet, as far as
    this side knows: what waits in the connection's buffer here, and in the
    socket's send queue (``TIOCOUTQ``, where the system has it)."""
    if transport.is_closing():
        return 0
    waiting = 0
    if isinstance(transport, asyncio.WriteTransport):
        waiting = int(transport.get_write_buffer_size())
    sock = transport.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            queued = array.array("i", [0])
            fcntl.ioctl(sock.fileno(), termios.TIOCOUTQ, queued)
            waiting += queued[0]
    return waiting


def _news(hub: Hub, tick: int) -> bool:
    """Whether a stream that sent ``tick`` has something to send (or must end)."""
    return hub.closing or (hub.tick != tick and hub.state is not None)


class Hub:
    """The newest state, taken once per look for every client."""

    def __init__(self, watch: Watch, options: LiveOptions) -> None:
        self.watch = watch
        self.options = options
        self.state: dict[str, Any] | None = None
        self.tick = 0
        self.closing = False
        self.clients = 0
        self.streams: list[asyncio.BaseTransport] = []  # the streams' connections, oldest first
        self.changed = asyncio.Condition()

    def make_room(self, most: int) -> None:
        """At most ``most`` - 1 streams left open: end the one whose client
        reads least (the most bytes written to it still unread), else the
        oldest, for a new one to take its place."""
        while self.streams and len(self.streams) >= most:
            order = {id(t): k for k, t in enumerate(self.streams)}
            victim = max(self.streams, key=lambda t: (_unread(t), -order[id(t)]))
            self.streams.remove(victim)
            victim.close()

    async def run(self) -> None:
        loop = asyncio.get_running_loop()
        seq, last = -1, -1e9
        while not self.closing:
            if self.clients == 0 and self.state is not None:  # nobody watches: rest
                await asyncio.sleep(self.options.poll)
                continue
            now = loop.time()
            newest = self.watch.seq
            if newest != seq or now - last >= self.options.state_every:
                last = now
                try:
                    state = self.watch.state()
                except Exception:  # the page goes on with what it showed; said once a pass
                    logging.getLogger(__name__).exception("the live page could not be updated")
                    await asyncio.sleep(self.options.poll)
                    continue
                if newest != seq or state != self.state:
                    seq = newest
                    self.state = state
                    async with self.changed:
                        self.tick += 1
                        self.changed.notify_all()
            await asyncio.sleep(self.options.poll)

    async def close(self) -> None:
        self.closing = True
        async with self.changed:
            self.changed.notify_all()


class LiveServer:
    """The page's server on a daemon thread: :meth:`start`, then :meth:`stop`."""

    def __init__(self, watch: Watch, address: Address, options: LiveOptions | None = None) -> None:
        self.watch = watch
        self.address = address
        self.options = options or LiveOptions()
        self.port = 0
        self._files = {
            name: (resources.files("cfgplan.live") / "static" / name).read_bytes()
            for name in STATIC
        }
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stopping: asyncio.Event | None = None
        self._ready = threading.Event()
        self._failed: BaseException | None = None
        self._thread: threading.Thread | None = None
        self._hub: Hub | None = None
        self._only_loopback = _loopback(address.host)

    # -- life ------------------------------------------------------------------

    def start(self) -> str:
        """Bind the address (an ``OSError`` if it cannot be), serve on a
        thread, and return the page's URL."""
        family = socket.AF_INET6 if ":" in self.address.host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((self.address.host, self.address.port))
            sock.listen(16)
        except OSError:
            sock.close()
            raise
        self.port = int(sock.getsockname()[1])
        self._thread = threading.Thread(
            target=self._serve, args=(sock,), name="cfgplan live page", daemon=True
        )
        self._thread.start()
        if not self._ready.wait(self.options.start_timeout):
            raise OSError(
                f"the live page's server did not start within {self.options.start_timeout:g} s"
            )
        if self._failed is not None:
            raise OSError(f"the live page's server did not start: {self._failed}")
        return self.address.url(self.port)

    def stop(self) -> None:
        """End the streams and the server, within :attr:`LiveOptions.stop_timeout` or so."""
        loop, stopping, thread = self._loop, self._stopping, self._thread
        if loop is None or stopping is None or thread is None:
            return
        with contextlib.suppress(RuntimeError):  # the loop is already closed
            loop.call_soon_threadsafe(stopping.set)
        thread.join(self.options.stop_timeout + 1)

    def _serve(self, sock: socket.socket) -> None:
        loop = asyncio.new_event_loop()
        self._loop = loop
        try:
            loop.run_until_complete(self._main(sock))
        except BaseException as exc:  # told to start(); the run goes on without its page
            self._failed = exc
            self._ready.set()
        finally:
            sock.close()
            loop.close()

    async def _main(self, sock: socket.socket) -> None:
        self._stopping = asyncio.Event()
        hub = Hub(self.watch, self.options)
        app = web.Application(middlewares=[self._guard])
        self._hub = hub
        app.router.add_get("/", self._index)
        app.router.add_get("/static/{name}", self._static)
        app.router.add_get("/events", self._events)
        app.router.add_get("/state.json", self._state)
        app.router.add_get("/drawing.svg", self._svg)
        app.router.add_get("/drawing.dot", self._dot)
        runner = web.AppRunner(
            app, access_log=None, shutdown_timeout=self.options.stop_timeout, handle_signals=False
        )
        await runner.setup()
        await web.SockSite(runner, sock).start()
        polling = asyncio.create_task(hub.run())
        self._ready.set()
        try:
            await self._stopping.wait()
        finally:
            await hub.close()
            polling.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await polling
            await runner.cleanup()

    # -- answers -----------------------------------------------------------------

    @web.middleware
    async def _guard(self, request: web.Request, handler: Any) -> web.StreamResponse:
        if self._only_loopback and not _loopback(_hostname(request.host)):
            raise web.HTTPForbidden(text="this page answers only to a loopback address\n")
        response: web.StreamResponse = await handler(request)
        return response

    def _reply(self, body: bytes, content_type: str) -> web.Response:
        response = web.Response(body=body, headers=HEADERS)
        response.headers["Content-Type"] = content_type
        return response

    async def _index(self, request: web.Request) -> web.Response:
        return self._reply(self._files["index.html"], STATIC["index.html"])

    async def _static(self, request: web.Request) -> web.Response:
        name = request.match_info["name"]
        if name not in STATIC or name == "index.html":
            raise web.HTTPNotFound()
        return self._reply(self._files[name], STATIC[name])

    async def _state(self, request: web.Request) -> web.Response:
        body = {**self.watch.state(), "timeline": self.watch.entries(0)}
        return self._reply(json.dumps(body).encode(), "application/json")

    async def _drawing(self) -> tuple[int, str, str | None]:
        return await asyncio.get_running_loop().run_in_executor(None, self.watch.drawing)

    async def _svg(self, request: web.Request) -> web.Response:
        number, _, svg = await self._drawing()
        if svg is None:
            raise web.HTTPNotFound(text="no drawing: see /drawing.dot\n")
        response = self._reply(svg.encode(), "image/svg+xml")
        response.headers["X-Drawing"] = str(number)
        return response

    async def _dot(self, request: web.Request) -> web.Response:
        number, source, _ = await self._drawing()
        response = self._reply(source.encode(), "text/plain; charset=utf-8")
        response.headers["X-Drawing"] = str(number)
        return response

    async def _events(self, request: web.Request) -> web.StreamResponse:
        hub = self._hub
        assert hub is not None  # set before the site starts
        transport = request.transport
        if transport is None:  # the client left already
            raise web.HTTPServiceUnavailable(text="the connection is gone\n")
        hub.make_room(self.options.clients)
        hub.streams.append(transport)
        hub.clients += 1
        try:
            response = web.StreamResponse(headers={**HEADERS, "X-Accel-Buffering": "no"})
            response.content_type = "text/event-stream"
            await response.prepare(request)
            await self._stream(hub, response)
            return response
        finally:
            hub.clients -= 1
            with contextlib.suppress(ValueError):
                hub.streams.remove(transport)

    async def _stream(self, hub: Hub, response: web.StreamResponse) -> None:
        seen, tick = 0, -1
        timeout = self.options.write_timeout
        await asyncio.wait_for(response.write(b"retry: 1000\n\n"), timeout)
        while not hub.closing:
            async with hub.changed:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(
                        hub.changed.wait_for(partial(_news, hub, tick)),
                        self.options.heartbeat,
                    )
            if hub.closing:
                break
            if hub.tick == tick or hub.state is None:
                message = b": still here\n\n"
            else:
                tick = hub.tick
                entries = self.watch.entries(seen)
                if entries:
                    seen = entries[-1]["seq"]
                payload = json.dumps({"state": hub.state, "entries": entries})
                message = f"data: {payload}\n\n".encode()
            try:
                await asyncio.wait_for(response.write(message), timeout)
            except (TimeoutError, ConnectionError, RuntimeError):  # (a stream ended to make room)
                break
