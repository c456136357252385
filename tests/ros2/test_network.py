"""A cfgplan robot seen by a plain zenoh-python "ROS 2 node" (slow, loopback).

Cross-door, 6.2.2 step 2, each robot its own process (as
tests/reconfigure/test_network.py): Emil runs with ``--ros2``, his compass
fails at cycle 40 and the society switches. The test's own Zenoh session,
written from rmw_zenoh's design document alone (the key expression and
token layout spelled out literally below, not taken from
:mod:`cfgplan.ros2`), must receive the failure and the switch on
``/cfgplan/events`` as CDR ``std_msgs/msg/String`` (decoded by rosbags) with
33-byte attachments, and see the node's and publisher's liveliness tokens
under ``@ros2_lv/0/``. Hermetic: loopback, free ports, scouting off, bounded
waits, every process stopped by its pid (:mod:`tests.runtime.netutil`).
"""

from __future__ import annotations

import json
import struct
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import xxhash
from rosbags.typesys import Stores, get_typestore

from tests.backends.support import DOMAINS, EXAMPLE_IMPL
from tests.runtime.netutil import endpoint, free_port, hermetic_config, processes, wait_for

zenoh = pytest.importorskip("zenoh")

STEP2 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
]
LIMIT = 90.0  # seconds: two interpreters, a Zenoh handshake and a run, on a loaded machine
HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
TYPE = "std_msgs::msg::dds_::String_"
TOPIC = f"0/cfgplan/events/{TYPE}/{HASH}"
"""design.md: <domain_id>/<fully qualified name>/<type name>/<type hash>."""


class RosNode:
    """What a ROS 2 subscriber of /cfgplan/events would see, from plain zenoh-python."""

    def __init__(self, config: Path, port: int) -> None:
        conf = zenoh.Config.from_file(str(config))
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("listen/endpoints", json.dumps([endpoint(port)]))
        self.session = zenoh.open(conf)
        self.lock = threading.Lock()
        self.messages: list[tuple[bytes, bytes | None]] = []
        self.tokens: set[str] = set()
        self.subscriber = self.session.declare_subscriber(TOPIC, self.on_message)
        self.watcher = self.session.liveliness().declare_subscriber(
            "@ros2_lv/0/**", self.on_token, history=True
        )

    def on_message(self, sample: Any) -> None:
        extra = None if sample.attachment is None else sample.attachment.to_bytes()
        with self.lock:
            self.messages.append((sample.payload.to_bytes(), extra))

    def on_token(self, sample: Any) -> None:
        if sample.kind == zenoh.SampleKind.PUT:
            with self.lock:
                self.tokens.add(str(sample.key_expr))

    def events(self) -> list[tuple[dict[str, Any], bytes | None]]:
        store = get_typestore(Stores.ROS2_JAZZY)
        with self.lock:
            got = list(self.messages)
        out = []
        for payload, extra in got:
            assert payload[:4] == b"\x00\x01\x00\x00"  # CDR little endian, options 0
            text = store.deserialize_cdr(payload, "std_msgs/msg/String").data
            out.append((json.loads(text), extra))
        return out

    def close(self) -> None:
        self.session.close()


@pytest.fixture
def ros_node(tmp_path: Path) -> Iterator[tuple[RosNode, int]]:
    port = free_port()
    node = RosNode(hermetic_config(tmp_path), port)
    try:
        yield node, port
    finally:
        node.close()


@pytest.mark.slow
def test_a_ros_node_sees_the_robot_and_receives_its_switch(
    tmp_path: Path, ros_node: tuple[RosNode, int]
) -> None:
    node, node_port = ros_node
    config = str(hermetic_config(tmp_path))
    emil_port = free_port()
    common = ["--zenoh-config", config, "--society", "ros2-test", "--lease", "1", "--rate", "20"]
    run = ["-m", "cfgplan", "run", *STEP2, "--impl", str(EXAMPLE_IMPL), *common]
    with processes() as running:
        emil = running.start(
            [
                *run, "--robot", "Emil", "--listen", endpoint(emil_port),
                "--connect", endpoint(node_port), "--cycles", "200",
                "--ros2", "--ros-domain-id", "0",
                "--inject", "fail compass(Emil) at cycle 40",
            ],
            tmp_path / "emil.log",
        )  # fmt: skip
        running.start(
            [
                *run, "--robot", "Pippi", "--listen", endpoint(free_port()),
                "--connect", endpoint(emil_port),
            ],
            tmp_path / "pippi.log",
        )  # fmt: skip

        def switched() -> dict[str, Any] | None:
            return next((e for e, _ in node.events() if e["event"] == "switch"), None)

        switch = wait_for("the switch on /cfgplan/events", switched, LIMIT)

        def announced() -> dict[str, Any] | None:
            # The events' publisher: each global channel Emil sends on has an
            # MP token of its own too (/cfgplan/channel/...).
            with node.lock:
                kinds = {
                    t.split("/")[5]: t
                    for t in node.tokens
                    if "/cfgplan_Emil" in t and ("/MP/" not in t or "/%cfgplan%events/" in t)
                }
            return kinds if {"NN", "MP"} <= set(kinds) else None

        tokens = wait_for("Emil's node and publisher tokens", announced, 10.0)
        assert emil.poll() is None or emil.returncode == 0
    assert (switch["robot"], switch["from_cost"], switch["to_cost"]) == ("Emil", 44, 47)
    events = node.events()
    names = [e["event"] for e, _ in events]
    assert names.index("failure") < names.index("switch")
    assert not set(names) - {"failure", "recovery", "switch", "no-configuration"}
    failure = next(e for e, _ in events if e["event"] == "failure")
    assert failure["resource"] == "compass(Emil)"
    # design.md "Graph Cache": @ros2_lv/<domain>/<session>/<node id>/<node id>/NN/%/%/<name>
    nn = tokens["NN"].split("/")
    assert nn[0:2] == ["@ros2_lv", "0"] and nn[3] == nn[4]
    assert nn[5:] == ["NN", "%", "%", "cfgplan_Emil"]
    mp = tokens["MP"].split("/")
    assert mp[2:4] == nn[2:4] and mp[4] != nn[4]  # the same session and node, its own id
    assert mp[5:] == ["MP", "%", "%", "cfgplan_Emil", "%cfgplan%events", TYPE, HASH, "::,10:,:,:,,"]
    # design.md "Publishers": int64 LE sequence number and timestamp, length 16, the GID
    gid = xxhash.xxh3_128_digest(tokens["MP"].encode())[::-1]  # low64, high64 little endian
    numbers = []
    for _, extra in events:
        assert extra is not None and len(extra) == 33 and extra[16] == 16
        number, stamp = struct.unpack_from("<qq", extra)
        assert extra[17:] == gid and stamp > 1_700_000_000 * 10**9
        numbers.append(number)
    assert numbers == list(range(1, len(numbers) + 1))
