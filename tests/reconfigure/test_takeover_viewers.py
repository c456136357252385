"""The live page and Foxglove follow a takeover (5.5).

The 6.2.2 sequence, each robot its own process; Emil, the helper, serves his
live page (``--live``) and Foxglove (``--foxglove``). Pippi, the coordinator,
is killed: Emil takes over and stops safely (every configuration of Pippi's
crossing needs her). From then on his page says that he coordinates, that
nothing runs and why, and draws nothing; Foxglove's connection graph loses
the configuration's channels, and the society's topics are Emil's. Pippi
started again steps down for Emil, who plans with her: the page shows his
switch (its id, its cost, a new drawing), and the graph has the channels
again.

Before, both showed the view of a helper for the whole run: Pippi the
coordinator, the first configuration's drawing and graph, whatever Emil did.
Hermetic: loopback, free ports, scouting off, bounded waits, every process
stopped by its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import json
import os
import re
import signal
import time
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from tests.reconfigure.test_network_restart import _after
from tests.reconfigure.test_network_takeover import LIMIT, SERVED, _society, _start
from tests.runtime.netutil import processes, wait_for

SUBPROTOCOL = "foxglove.sdk.v1"
CHANNELS = "/cfgplan/channels/"


def _state(url: str) -> dict[str, Any]:
    with urllib.request.urlopen(f"{url}state.json", timeout=10) as answer:
        state: dict[str, Any] = json.loads(answer.read())
        return state


class Graph:
    """Foxglove's connection graph as a client sees it: every update, in order."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.updates: list[dict[str, Any]] = []
        self.published: dict[str, list[str]] = {}

    def drain(self) -> None:
        while True:
            try:
                frame = self.ws.recv(timeout=0.1)
            except TimeoutError:
                return
            if isinstance(frame, str):
                message = json.loads(frame)
                if message["op"] == "connectionGraphUpdate":
                    self.updates.append(message)
                    for topic in message.get("publishedTopics", []):
                        self.published[topic["name"]] = topic["publisherIds"]
                    for name in message.get("removedTopics", []):
                        self.published.pop(name, None)

    def channels(self) -> list[str]:
        return sorted(t for t in self.published if t.startswith(CHANNELS))

    def until(self, what: str, holds: Any, limit: float = 10.0) -> None:
        deadline = time.monotonic() + limit
        while time.monotonic() < deadline:
            self.drain()
            if holds():
                return
        raise AssertionError(f"not within {limit} s: {what}; graph: {self.published}")


@pytest.mark.slow
def test_the_live_page_and_foxglove_follow_a_takeover(tmp_path: Path) -> None:
    from websockets.sync.client import connect
    from websockets.typing import Subprotocol

    viewers = ("--live", "127.0.0.1:0", "--foxglove", "127.0.0.1:0")
    with processes() as running:
        emil, pippi, nets = _society(running, tmp_path, "takeover-viewers", emil=viewers)
        log = (tmp_path / "emil.log").read_text("utf-8")
        page = re.search(r"live page: (http://127\.0\.0\.1:\d+/)", log)
        fox = re.search(r"foxglove: (ws://127\.0\.0\.1:\d+)", log)
        assert page is not None and fox is not None, log
        url = page.group(1)
        before = _state(url)
        with connect(fox.group(1), subprotocols=[Subprotocol(SUBPROTOCOL)], open_timeout=10) as ws:
            ws.send(json.dumps({"op": "subscribeConnectionGraph"}))
            graph = Graph(ws)
            graph.until("the first graph", lambda: graph.channels())
            first_channels = graph.channels()
            assert graph.published["/cfgplan/switches"] == ["Pippi"]
            os.kill(pippi.pid, signal.SIGKILL)  # type: ignore[attr-defined]
            killed = time.time()
            emil_trace = tmp_path / "emil.jsonl"
            takeover = wait_for("Emil takes over", _after(emil_trace, killed, "takeover"), LIMIT)
            t = float(takeover["t"])  # type: ignore[arg-type]
            stop = wait_for("Emil stops", _after(emil_trace, t - 1e-6, "no-configuration"), 10)
            graph.until("no channel, Emil's topics", lambda: not graph.channels())
            assert graph.published["/cfgplan/switches"] == ["Emil"]
            halted = _state(url)
            again = tmp_path / "again"
            again.mkdir()
            _, back_trace, _ = _start(running, again, "Pippi", nets["Pippi"])
            switch = wait_for("Emil's switch", _after(emil_trace, t, "switch"), LIMIT)
            served = _after(back_trace, float(switch["t"]), "call", **SERVED)  # type: ignore[arg-type]
            wait_for("Pippi's crossing again", served, LIMIT)
            after = _state(url)
            graph.until("the channels again", lambda: len(graph.channels()) == len(first_channels))
        assert emil.wait(timeout=LIMIT) == 0  # type: ignore[attr-defined]
    assert (before["coordinator"], before["decides"], before["drawing"]) == ("Pippi", False, 1)
    assert (halted["coordinator"], halted["decides"]) == ("Emil", True), halted
    assert (halted["configuration"], halted["drawing"], halted["cost"]) == (stop["id"], 0, None)
    assert halted["halted"], halted
    assert (after["configuration"], after["cost"], after["halted"]) == (switch["id"], 44, None)
    assert after["drawing"] > halted["drawing"] and after["drawing"] != before["drawing"]
    assert after["fallbacks_note"] == "not computed ahead in a sequence of configurations (7.3)"
