"""``cfgplan run ... --foxglove [HOST:]PORT``: the run served to Foxglove live.

A WebSocket client (the ``websockets`` package, speaking the Foxglove
WebSocket protocol as Foxglove does: subprotocol ``foxglove.sdk.v1``,
``subscribe`` and ``subscribeConnectionGraph``, binary message data)
connects to a cross-door run (6.2.2 step 2) on loopback, subscribes to the
switch channel, and must receive the switch injected at cycle 40 within a
bounded wait; the connection graph must be the configuration's, and change
at the switch.
"""

from __future__ import annotations

import json
import re
import struct
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from cfgplan.live.address import Address
from cfgplan.record import channels
from cfgplan.runtime import schema as s
from cfgplan.runtime.errors import RunError
from tests.runtime.netutil import processes, wait_for

ROOT = Path(__file__).resolve().parents[2]
CROSS = ROOT / "domains" / "cross-door"
SUBPROTOCOL = "foxglove.sdk.v1"
COMPASS = "/cfgplan/channels/F10->F12_(global-orient_Emil)"
"""Emil's compass's channel to Pippi, in the first configuration only."""


@pytest.mark.slow
def test_a_client_sees_the_graph_and_receives_the_switch(tmp_path: Path) -> None:
    """Subscribed to /cfgplan/switches (advertised with SwitchEvent's JSON Schema
    before any switch), the client receives the switch 44 -> 47 at cycle 40;
    the graph advertised has the configuration's channels, published by their
    source functionality, subscribed by their target, and after the switch
    loses the failed compass's channel."""
    from websockets.sync.client import connect
    from websockets.typing import Subprotocol

    log = tmp_path / "run.log"
    args = [
        "-m",
        "cfgplan",
        "run",
        str(CROSS / "domain.lisp"),
        str(CROSS / "state-6.2.2-step2.lisp"),
        "--impl",
        str(ROOT / "examples" / "cross-door" / "impl.py"),
        "--rate",
        "10",
        "--cycles",
        "600",
        "--inject",
        "fail compass(Emil) at cycle 40",
        "--foxglove",
        "127.0.0.1:0",
    ]
    with processes() as running:
        process = running.start(args, log)

        def url() -> dict[str, Any] | None:
            found = re.search(r"foxglove: (ws://127\.0\.0\.1:\d+)", log.read_text("utf-8"))
            return {"url": found.group(1)} if found else None

        address = str(wait_for("the server's URL", url, 60)["url"])
        graphs: list[dict[str, Any]] = []
        switch: dict[str, Any] | None = None
        with connect(address, subprotocols=[Subprotocol(SUBPROTOCOL)], open_timeout=10) as ws:
            advertised: dict[str, dict[str, Any]] = {}
            deadline = time.monotonic() + 60
            subscribed = False
            while switch is None and time.monotonic() < deadline:
                assert process.poll() is None, "the run ended"
                try:
                    frame = ws.recv(timeout=1)
                except TimeoutError:
                    continue
                if isinstance(frame, bytes):
                    assert frame[0] == 1  # message data
                    subscription, _ = struct.unpack_from("<IQ", frame, 1)
                    if subscription == 1:
                        switch = json.loads(frame[13:])
                    continue
                message = json.loads(frame)
                if message["op"] == "advertise":
                    advertised.update({c["topic"]: c for c in message["channels"]})
                elif message["op"] == "connectionGraphUpdate":
                    graphs.append(message)
                if not subscribed and "/cfgplan/switches" in advertised:
                    channel = advertised["/cfgplan/switches"]
                    assert channel["encoding"] == "json"
                    assert channel["schemaEncoding"] == "jsonschema"
                    assert channel["schemaName"] == "cfgplan.trace.SwitchEvent"
                    assert json.loads(channel["schema"]) == s.SwitchEvent.model_json_schema(
                        by_alias=True
                    )
                    subscribe = {"id": 1, "channelId": channel["id"]}
                    ws.send(json.dumps({"op": "subscribe", "subscriptions": [subscribe]}))
                    ws.send(json.dumps({"op": "subscribeConnectionGraph"}))
                    subscribed = True
            assert switch is not None, "no switch received within 60 s"
            # the graph update the switch makes comes right after it
            end = time.monotonic() + 10
            while time.monotonic() < end and not any(
                COMPASS in g.get("removedTopics", []) for g in graphs
            ):
                try:
                    frame = ws.recv(timeout=1)
                except TimeoutError:
                    continue
                if isinstance(frame, str):
                    message = json.loads(frame)
                    if message["op"] == "connectionGraphUpdate":
                        graphs.append(message)
        assert "/cfgplan/Emil/freshness" in advertised and "/cfgplan/failures" in advertised
    assert (switch["from_cost"], switch["to_cost"], switch["cycle"]) == (44, 47, 40)
    assert switch["cause"] == "compass(Emil) failed"
    first = graphs[0]
    published = {t["name"]: t["publisherIds"] for t in first["publishedTopics"]}
    subscribed_to = {t["name"]: t["subscriberIds"] for t in first["subscribedTopics"]}
    assert published[COMPASS] == ["F10: compass(Emil)"]
    assert subscribed_to[COMPASS] == ["F12: measure-robot-orient-compass(Pippi, Emil)"]
    assert published["/cfgplan/switches"] == ["Emil"]  # the coordinator
    assert published["/cfgplan/Pippi/calls"] == ["Pippi"]
    assert any(COMPASS in g.get("removedTopics", []) for g in graphs[1:]), graphs[1:]


def test_the_graph_of_a_configuration() -> None:
    """Each channel of the configuration is a topic from its source
    functionality to its target; local channels too."""
    from cfgplan.cli.options import choose, load_problem
    from cfgplan.record.foxglove_live import graph_of

    problem = load_problem(
        CROSS / "domain.lisp", CROSS / "state-6.2.2-step2.lisp", None, None, sequence=True
    )
    config = choose(problem, 1)
    graph = graph_of(config)
    assert len(graph.published) == len(config.channels) == len(graph.subscribed)
    nodes = {str(f) for f in config.functionalities}
    for topic in graph.published:
        assert topic.startswith("/cfgplan/channels/F")
        assert set(graph.published[topic]) <= nodes and set(graph.subscribed[topic]) <= nodes
    assert graph_of(None).published == {}
    assert channels.segment("F7->F3 (pos Emil Door1)") == "F7->F3_(pos_Emil_Door1)"


def test_without_the_sdk_foxglove_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    """With foxglove-sdk missing, --foxglove is a clear error naming the extra."""
    from cfgplan.record.launch import open_foxglove

    monkeypatch.setitem(sys.modules, "foxglove", None)
    with pytest.raises(RunError) as caught:
        open_foxglove(Address("127.0.0.1", 0), None, None, None, (), "")  # type: ignore[arg-type]
    assert "--foxglove needs the foxglove-sdk package" in str(caught.value)
    assert caught.value.hint == "pip install 'cfgplan[foxglove]'"


def test_the_subprotocol_the_server_speaks_is_the_one_the_docs_name() -> None:
    """foxglove-sdk 0.30's server accepts a client offering ``foxglove.sdk.v1``
    and refuses one offering only the older ``foxglove.websocket.v1`` (HTTP
    400): the how-to names both, so a user of an older client knows why it
    cannot connect."""
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect
    from websockets.typing import Subprotocol

    from cfgplan.cli.options import choose, load_problem
    from cfgplan.record.foxglove_live import serve

    docs = (ROOT / "docs" / "how-to" / "record-a-run.md").read_text("utf-8")
    named = re.search(r"subprotocol\s+`(foxglove\.[a-z]+\.v\d+)`", docs)
    assert named is not None, "the how-to names no subprotocol"
    assert "`foxglove.websocket.v1`" in docs
    problem = load_problem(
        CROSS / "domain.lisp", CROSS / "state-6.2.2-step2.lisp", None, None, sequence=True
    )
    live = serve(Address("127.0.0.1", 0), "subprotocol", choose(problem, 1))
    try:
        url = f"ws://127.0.0.1:{live.server.port}"
        with connect(url, subprotocols=[Subprotocol(named[1])], open_timeout=10) as ws:
            assert ws.subprotocol == named[1] == SUBPROTOCOL
            assert json.loads(ws.recv(timeout=10))["op"] == "serverInfo"
        with (
            pytest.raises(InvalidStatus) as refused,
            connect(url, subprotocols=[Subprotocol("foxglove.websocket.v1")], open_timeout=10),
        ):
            pass
        assert refused.value.response.status_code == 400
    finally:
        live.stop()
