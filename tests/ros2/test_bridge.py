"""The ROS 2 event bridge (:mod:`cfgplan.ros2.bridge`) on a stand-in Zenoh
session, and ``cfgplan run``'s ``--ros2`` options; the real session is in
tests/ros2/test_network.py (slow)."""

from __future__ import annotations

import json
from typing import Any

import pytest
from typer.testing import CliRunner

import cfgplan.cli.run  # noqa: F401  (loads the command module)
from cfgplan.cli.app import app
from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.ros2.bridge import BridgeOptions, EventBridge, domain_id_of, open_bridge
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Adaptation, Lifecycle
from tests.backends.support import DOMAINS, EXAMPLE_IMPL

ZID = "0123456789abcdef0123456789abcdef"


class Declared:
    def __init__(self, key: str, puts: list[tuple[str, bytes, bytes]] | None = None) -> None:
        self.key, self.puts, self.undeclared = key, puts, False

    def put(self, payload: bytes, *, attachment: bytes) -> None:
        assert self.puts is not None
        self.puts.append((self.key, payload, attachment))

    def undeclare(self) -> None:
        self.undeclared = True


class Session:
    """What the bridge uses of a zenoh-python session."""

    def __init__(self) -> None:
        self.tokens: list[Declared] = []
        self.puts: list[tuple[str, bytes, bytes]] = []
        self.closed = False

    def zid(self) -> str:
        return ZID

    def liveliness(self) -> Session:
        return self

    def declare_token(self, key: str) -> Declared:
        self.tokens.append(Declared(key))
        return self.tokens[-1]

    def declare_publisher(self, key: str) -> Declared:
        return Declared(key, self.puts)

    def is_closed(self) -> bool:
        return self.closed


def test_the_bridge_announces_a_node_and_a_publisher() -> None:
    """Tokens ``NN`` and ``MP`` of node ``cfgplan_Emil``, publisher on
    ``/cfgplan/events`` as std_msgs/msg/String, reliable keep last 10."""
    session = Session()
    bridge = EventBridge(session, "Emil", BridgeOptions(domain_id=3))
    hashed = wire.type_hash("std_msgs/msg/String")
    assert [t.key for t in session.tokens] == [
        f"@ros2_lv/3/{ZID}/0/0/NN/%/%/cfgplan_Emil",
        f"@ros2_lv/3/{ZID}/0/1/MP/%/%/cfgplan_Emil/%cfgplan%events/"
        f"std_msgs::msg::dds_::String_/{hashed}/::,10:,:,:,,",
    ]
    assert bridge.key_expr == f"3/cfgplan/events/std_msgs::msg::dds_::String_/{hashed}"
    assert bridge.gid == wire.gid(session.tokens[1].key)
    bridge.close()
    assert all(t.undeclared for t in session.tokens)


def test_the_chosen_adaptation_events_are_published_in_order() -> None:
    """Switches and failures go out as JSON in a CDR String, sequence numbers
    1, 2, ... and the publisher's GID in the attachment; other events do not."""
    session = Session()
    bridge = EventBridge(session, "Emil")
    switch = Adaptation(robot="Emil", cycle=41, t=1.5, what="switch", info=(("id", 1),))
    bridge(Lifecycle(robot="Emil", what="start"))
    bridge(Adaptation(robot="Emil", what="install", info=(("id", 1),)))
    bridge(Adaptation(robot="Emil", what="failure", info=(("resource", "compass(Emil)"),)))
    bridge(switch)
    assert len(session.puts) == 2
    key, payload, _ = session.puts[1]
    assert key == bridge.key_expr
    assert json.loads(wire.string_of_cdr(payload)) == switch.record()
    first, second = (wire.parse_attachment(p[2]) for p in session.puts)
    assert (first.sequence_number, second.sequence_number) == (1, 2)
    assert first.gid == second.gid == bridge.gid
    assert 0 < first.source_timestamp <= second.source_timestamp


def test_a_closed_session_is_counted_not_raised() -> None:
    """An event after the session closed (the run ending) does not break the robot's loop."""

    class Closed(Declared):
        def put(self, payload: bytes, *, attachment: bytes) -> None:
            raise RuntimeError("session closed")

    session = Session()
    session.declare_publisher = lambda key: Closed(key)  # type: ignore[method-assign]
    bridge = EventBridge(session, "Emil")
    bridge(Adaptation(robot="Emil", what="recovery"))
    assert (bridge.published, bridge.failed) == (0, 1)


def test_the_domain_is_the_option_then_ros_domain_id_then_0() -> None:
    """``--ros-domain-id`` wins; else ``ROS_DOMAIN_ID`` as every ROS 2 program; else 0."""
    assert domain_id_of(None, {}) == 0
    assert domain_id_of(None, {"ROS_DOMAIN_ID": "12"}) == 12
    assert domain_id_of(5, {"ROS_DOMAIN_ID": "12"}) == 5
    with pytest.raises(RunError, match="ROS_DOMAIN_ID='x' is not a ROS domain id"):
        domain_id_of(None, {"ROS_DOMAIN_ID": "x"})
    with pytest.raises(RunError, match="--ros-domain-id 300: a ROS domain id is 0 to 232"):
        domain_id_of(300, {})


def test_bad_names_and_transports_are_refused() -> None:
    """A topic that is not a ROS 2 name, or a transport without a Zenoh session."""
    with pytest.raises(RunError, match="not an absolute ROS 2 topic name"):
        EventBridge(Session(), "Emil", BridgeOptions(topic="events"))
    with pytest.raises(RunError, match="run it with --robot NAME"):
        open_bridge(object(), "Emil")


STEP2 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--ros2"], "give --robot NAME"),
        (["--ros-domain-id", "3"], "give --ros2"),
        (["--robot", "Emil", "--ros2", "--keys", "keys"], "cannot be combined with --keys"),
        (["--robot", "Emil", "--ros2", "--ros-domain-id", "-1"], "greater than or equal to 0"),
        (["--robot", "Emil", "--ros2", "--ros-domain-id", "233"], "less than or equal to 232"),
    ],
)
def test_run_refuses_ros2_options_it_cannot_use(extra: list[str], message: str) -> None:
    """--ros2 needs a robot of its own process; --ros-domain-id needs --ros2 (exit 2)."""
    args = ["run", *STEP2, "--impl", str(EXAMPLE_IMPL), "--cycles", "1", *extra]
    result: Any = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert message in result.output
