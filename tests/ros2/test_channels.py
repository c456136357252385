"""Global channels as ROS 2 topics (``--ros2``), seen by a plain zenoh-python node.

The robot's side is :class:`~cfgplan.ros2.bridge.EventBridge` on a real
Zenoh session, given the sends of a global channel as the runtime records
them; the ROS side, another session in this process, is written from
rmw_zenoh's design document alone: the key expression of
``/cfgplan/channel/pos/Pippi/Door1`` spelled out literally, the String's CDR
read by rosbags, the attachment unpacked by hand. Hermetic: loopback, a free
port, scouting off, bounded waits.
"""

from __future__ import annotations

import json
import struct
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from cfgplan.ros2.bridge import EventBridge, channel_topic
from cfgplan.runtime.events import Adaptation, Transfer
from cfgplan.runtime.transport import ChannelKey
from tests.runtime.netutil import endpoint, free_port, hermetic_config, wait_for

zenoh = pytest.importorskip("zenoh")
typesys = pytest.importorskip("rosbags.typesys")

STRING = "std_msgs::msg::dds_::String_"
HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
KEY = f"0/cfgplan/channel/pos/Pippi/Door1/{STRING}/{HASH}"
"""design.md: <domain_id>/<fully qualified name>/<type name>/<type hash>."""


def test_a_channel_topic_is_a_ros_name_of_its_data() -> None:
    """Each part of the data one name token; what a ROS name cannot hold becomes _."""
    assert channel_topic(("pos", "Pippi", "Door1")) == "/cfgplan/channel/pos/Pippi/Door1"
    assert channel_topic(("global-orient", "Emil")) == "/cfgplan/channel/global_orient/Emil"
    assert channel_topic(("at", "r2", "7")) == "/cfgplan/channel/at/r2/_7"


def _session(config: Path, listen: list[str], connect: list[str]) -> Any:
    conf = zenoh.Config.from_file(str(config))
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("listen/endpoints", json.dumps(listen))
    conf.insert_json5("connect/endpoints", json.dumps(connect))
    return zenoh.open(conf)


def test_a_ros_node_receives_each_send_of_a_global_channel(tmp_path: Path) -> None:
    """Two sends of pos(Pippi, Door1) arrive on its topic as JSON in a CDR String,
    sequence numbers 1 and 2 of their own publisher (the events' count apart),
    with the publisher's MP token under @ros2_lv/0/."""
    config, port = hermetic_config(tmp_path), free_port()
    ros = _session(config, [endpoint(port)], [])
    robot = _session(config, [], [endpoint(port)])
    got: list[tuple[bytes, bytes]] = []
    tokens: set[str] = set()
    lock = threading.Lock()

    def on_message(sample: Any) -> None:
        with lock:
            got.append((sample.payload.to_bytes(), sample.attachment.to_bytes()))

    def on_token(sample: Any) -> None:
        with lock:
            tokens.add(str(sample.key_expr))

    try:
        ros.declare_subscriber(KEY, on_message)
        ros.liveliness().declare_subscriber("@ros2_lv/0/**", on_token, history=True)
        bridge = EventBridge(robot, "Emil")
        key = ChannelKey("F7", "F3", ("pos", "Pippi", "Door1"))
        bridge(Adaptation(robot="Emil", what="switch"))  # the events' own publisher
        sends = [
            Transfer(robot="Emil", cycle=n, t=float(n), direction="send", channel=key,
                     other="Pippi", value=[0.695, -2.601], seq=n)
            for n in (1, 2)
        ]  # fmt: skip
        bridge(
            Transfer(robot="Emil", direction="receive", channel=key, other="Pippi", value=0, seq=9)
        )
        assert bridge.channels == {}  # a receive is the other robot's send: not published here

        def announced() -> dict[str, Any] | None:
            with lock:
                return {"ok": 1} if any("/NN/%/%/cfgplan_Emil" in t for t in tokens) else None

        wait_for("the robot's node token (the sessions linked)", announced, 30.0)
        time.sleep(0.5)  # the subscriber's declaration reaches the robot with the link
        for send in sends:
            bridge(send)

        def arrived() -> dict[str, Any] | None:
            with lock:
                return {"n": len(got)} if len(got) >= 2 else None

        wait_for("two messages of pos(Pippi, Door1)", arrived, 30.0)
        store = typesys.get_typestore(typesys.Stores.ROS2_JAZZY)
        with lock:
            messages = list(got)
            seen = set(tokens)
        texts = [
            json.loads(store.deserialize_cdr(p, "std_msgs/msg/String").data) for p, _ in messages
        ]
        assert texts[0]["event"] == "send" and texts[0]["channel"] == "F7->F3 (pos Pippi Door1)"
        assert texts[0]["to"] == "Pippi" and texts[0]["value"] == [0.695, -2.601]
        numbers = [struct.unpack_from("<q", extra)[0] for _, extra in messages]
        assert numbers == [1, 2] and all(len(extra) == 33 for _, extra in messages)
        wait_for(
            "the channel's MP token",
            lambda: (
                {"ok": 1}
                if any(
                    "/MP/%/%/cfgplan_Emil/%cfgplan%channel%pos%Pippi%Door1/" in t for t in tokens
                )
                else None
            ),
            10.0,
        )
        assert any(t.endswith(f"/{STRING}/{HASH}/::,10:,:,:,,") for t in seen | tokens)
        bridge.close()
    finally:
        robot.close()
        ros.close()
