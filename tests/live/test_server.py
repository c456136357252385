"""The live page's server (cfgplan.live.server): read-only, bounded, pushing
what the robots' thread hands it. Loopback only, a free port, every wait bounded."""

from __future__ import annotations

import http.client
import json
import time
from collections.abc import Iterator

import pytest

from cfgplan.live.address import Address
from cfgplan.live.model import Setup
from cfgplan.live.server import LiveOptions, LiveServer
from cfgplan.live.watch import Watch
from cfgplan.runtime.events import Adaptation
from tests.backends.support import cross_door_44

pytest.importorskip("aiohttp")


@pytest.fixture
def served() -> Iterator[tuple[Watch, LiveServer]]:
    problem, config = cross_door_44()
    setup = Setup("cross-door", ("Emil", "Pippi"), ("Emil", "Pippi"), "Emil", 44, time.time())
    watch = Watch(setup, config, problem.goal_call[1:])
    server = LiveServer(watch, Address("127.0.0.1", 0), LiveOptions(clients=2))
    server.start()
    try:
        yield watch, server
    finally:
        began = time.monotonic()
        server.stop()
        assert time.monotonic() - began < 5, "the server took too long to stop"


def _get(
    server: LiveServer, path: str, method: str = "GET", host: str | None = None
) -> tuple[int, dict[str, str], bytes]:
    connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    try:
        headers = {} if host is None else {"Host": host}
        connection.request(method, path, headers=headers)
        answer = connection.getresponse()
        return answer.status, dict(answer.getheaders()), answer.read()
    finally:
        connection.close()


def test_the_page_and_its_files_are_served_from_the_package(
    served: tuple[Watch, LiveServer],
) -> None:
    """Three files, each with a policy forbidding anything from elsewhere."""
    _, server = served
    status, headers, body = _get(server, "/")
    assert status == 200 and b"/static/page.js" in body
    assert "script-src 'self'" in headers["Content-Security-Policy"]
    for name in ("page.js", "page.css"):
        assert _get(server, f"/static/{name}")[0] == 200
    for name in ("/", "/static/page.js", "/static/page.css"):  # nothing loaded from elsewhere
        text = _get(server, name)[2].replace(b"http://www.w3.org/2000/svg", b"")
        assert b"http" not in text and b"//cdn" not in text
    assert _get(server, "/static/..%2Fserver.py")[0] == 404
    assert _get(server, "/static/server.py")[0] == 404
    status, headers, body = _get(server, "/drawing.svg")
    assert status == 200 and headers["X-Drawing"] == "1" and b"data-input" in body


def test_nothing_but_reading_is_allowed(served: tuple[Watch, LiveServer]) -> None:
    """POST and PUT are refused; a request addressed to another host name
    (DNS rebinding) is refused by a page on the loopback."""
    _, server = served
    assert _get(server, "/events", "POST")[0] == 405
    assert _get(server, "/", "PUT")[0] == 405
    assert _get(server, "/", host="attacker.example")[0] == 403
    # names that only start like a loopback address may be rebound to anything
    assert _get(server, "/", host="127.evil.example")[0] == 403
    assert _get(server, "/", host=f"127.0.0.1.nip.io:{server.port}")[0] == 403
    assert _get(server, "/", host=f"127.0.0.1:{server.port}")[0] == 200
    assert _get(server, "/", host=f"localhost:{server.port}")[0] == 200


def test_a_switch_is_pushed_to_the_page_at_once(served: tuple[Watch, LiveServer]) -> None:
    """The event stream's first message has the state and the timeline; a
    switch recorded later arrives within a fraction of a second."""
    watch, server = served
    connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    try:
        connection.request("GET", "/events")
        stream = connection.getresponse()
        assert stream.status == 200
        assert stream.getheader("Content-Type", "").startswith("text/event-stream")

        def message() -> dict[str, object]:
            while True:
                line = stream.readline()
                assert line, "the stream ended"
                if line.startswith(b"data: "):
                    data: dict[str, object] = json.loads(line[6:])
                    return data

        first = message()
        assert first["entries"] == []
        state = first["state"]
        assert isinstance(state, dict) and state["title"] == "cross-door"
        switched = time.time()
        watch(
            Adaptation(
                robot="Emil",
                t=switched,
                what="switch",
                info=(
                    ("id", 1),
                    ("cause", "test"),
                    ("to_cost", 47),
                    ("stopped", {"functionalities": []}),
                    ("started", {"functionalities": []}),
                ),
            )
        )
        while True:
            got = message()
            if got["entries"]:
                break
        assert time.time() - switched < 0.5
        (entry,) = got["entries"]  # type: ignore[misc]
        assert entry["kind"] == "switch" and entry["cause"] == "test"
    finally:
        connection.close()


def test_clients_holding_every_stream_cannot_lock_the_operator_out(
    served: tuple[Watch, LiveServer],
) -> None:
    """Measured: any few local processes could hold the page's streams
    (LiveOptions.clients) without reading them, and the operator's page was
    refused (503). Now a new stream takes the place of the one that reads
    least, else of the oldest: with both streams held by clients that never
    read, the operator's page gets its state, and one holder's stream ends
    (the other holder's is not ended for it); the streams never exceed the
    bound."""
    _, server = served
    holders = []
    try:
        for _ in range(2):
            connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
            connection.request("GET", "/events")
            holders.append(connection.getresponse())  # and never read
            assert holders[-1].status == 200
        time.sleep(0.5)
        operator = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
        try:
            operator.request("GET", "/events")
            stream = operator.getresponse()
            assert stream.status == 200
            while not (line := stream.readline()).startswith(b"data: "):
                assert line, "the operator's stream ended"
            assert json.loads(line[6:])["state"]["title"] == "cross-door"
        finally:
            operator.close()
        ended = []
        for holder in holders:
            holder.fp.raw._sock.settimeout(1.0)  # type: ignore[union-attr]
            deadline, over = time.monotonic() + 3.0, False
            try:
                while not over and time.monotonic() < deadline:
                    over = holder.readline() == b""
            except TimeoutError:
                pass
            ended.append(over)
        assert ended == [True, False]  # the oldest gave its place
    finally:
        for holder in holders:
            holder.close()


def test_an_address_in_use_is_a_clear_error() -> None:
    """Binding a port another server holds fails at start, not on a thread."""
    _, config = cross_door_44()
    setup = Setup("x", ("Emil",), ("Emil",), "Emil")
    first = LiveServer(Watch(setup, config), Address("127.0.0.1", 0))
    first.start()
    try:
        second = LiveServer(Watch(setup, config), Address("127.0.0.1", first.port))
        with pytest.raises(OSError):
            second.start()
    finally:
        first.stop()
