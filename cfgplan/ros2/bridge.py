"""A robot's reconfiguration events as the ROS 2 topic ``/cfgplan/events``.

``cfgplan run ... --robot NAME --ros2`` makes the robot's Zenoh session a ROS
2 node for rmw_zenoh (:mod:`cfgplan.ros2.rmw_zenoh`): it declares the node's
and the publisher's liveliness tokens, so ``ros2 node list`` shows
``/cfgplan_<robot>`` and ``ros2 topic list`` shows ``/cfgplan/events``, and
publishes every :class:`~cfgplan.runtime.events.Adaptation` event the robot
records whose name is in :attr:`BridgeOptions.events` (the switches,
failures, recoveries and safe stops of 5.5; the coordinator records the
switches, and so does a robot from the moment it takes over coordination,
which it says, as a coordinator says that it steps down) as a
``std_msgs/msg/String`` whose ``data`` is the event's trace line (JSON,
:meth:`~cfgplan.runtime.events.Event.record`), with rmw_zenoh's CDR payload
and attachment. ``ros2 topic echo /cfgplan/events`` on a machine
whose rmw_zenoh reaches the robot's session shows them.

Each global channel the robot writes (5.2: a value sent to a functionality of
another robot) is also a topic, ``/cfgplan/channel/<predicate>/<object>...``
of its data (``pos(Pippi, Door1)``: ``/cfgplan/channel/pos/Pippi/Door1``;
characters a ROS 2 name cannot hold become ``_``), a ``std_msgs/msg/String``
whose ``data`` is the send's trace line (JSON: channel, seq, to, value), one
message per send: :func:`channel_topic`. Its publisher and ``MP`` token are
declared at the channel's first send, and stay for the run.

The session is the robot's own (:attr:`ZenohTransport.session
<cfgplan.runtime.zenoh_transport.ZenohTransport.session>`); it closes with
the robot, and its tokens go with it.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Adaptation, Event, Transfer

__all__ = [
    "CHANNELS_TOPIC",
    "EVENTS_TOPIC",
    "BridgeOptions",
    "EventBridge",
    "channel_topic",
    "domain_id_of",
    "open_bridge",
]

EVENTS_TOPIC = "/cfgplan/events"
CHANNELS_TOPIC = "/cfgplan/channel"
"""The namespace of the global channels' topics."""
DOMAIN_ENV = "ROS_DOMAIN_ID"
MAX_DOMAIN_ID = 232
"""The largest ROS_DOMAIN_ID ROS 2 documents (its DDS port arithmetic); rmw_zenoh keeps the rule."""


def domain_id_of(given: int | None, env: Mapping[str, str] | None = None) -> int:
    """The ROS domain: ``--ros-domain-id`` if given, else ``ROS_DOMAIN_ID`` if
    set (as every ROS 2 program does; design.md: "the value of the
    ROS_DOMAIN_ID environment variable"), else 0."""
    env = os.environ if env is None else env
    if given is not None:
        value, where = given, "--ros-domain-id"
    else:
        text = env.get(DOMAIN_ENV, "").strip()
        if not text:
            return 0
        if not text.isdigit():
            raise RunError(f"{DOMAIN_ENV}={text!r} is not a ROS domain id (0 to {MAX_DOMAIN_ID})")
        value, where = int(text), DOMAIN_ENV
    if not 0 <= value <= MAX_DOMAIN_ID:
        raise RunError(f"{where} {value}: a ROS domain id is 0 to {MAX_DOMAIN_ID}")
    return value


def channel_topic(data: tuple[str, ...] | list[str], prefix: str = CHANNELS_TOPIC) -> str:
    """The topic of a global channel carrying ``data`` (``("pos", "Pippi",
    "Door1")``: ``/cfgplan/channel/pos/Pippi/Door1``), each part a valid ROS 2
    name token (:func:`cfgplan.ros2.rmw_zenoh.node_name_of`)."""
    return "/".join((prefix, *(wire.node_name_of(part) for part in data)))


@dataclass(frozen=True)
class BridgeOptions:
    """What the bridge announces and publishes."""

    domain_id: int = 0
    node: str | None = None  # None: cfgplan_<robot>
    namespace: str = "/"
    topic: str = EVENTS_TOPIC
    events: frozenset[str] = frozenset(
        {"switch", "failure", "recovery", "no-configuration", "takeover", "step-down"}
    )
    qos: wire.QoS = wire.PUBLISHER_QOS
    channels: str | None = CHANNELS_TOPIC
    """The namespace of the global channels' topics (``None``: not published)."""


class EventBridge:
    """One robot as a ROS 2 node publishing its events (a listener of the robot).

    Declares, on ``session`` (a zenoh-python session), the node's ``NN`` and
    the publisher's ``MP`` liveliness tokens and the publisher on the topic's
    key expression; :meth:`__call__` takes the robot's events. Never raises
    into the robot's loop: a message that cannot be put is counted in
    :attr:`failed`."""

    def __init__(self, session: Any, robot: str, options: BridgeOptions | None = None) -> None:
        self.options = options = options or BridgeOptions()
        try:
            wire.check_name(options.topic, "topic name")
            if options.namespace != "/":
                wire.check_name(options.namespace, "namespace")
        except ValueError as exc:
            raise RunError(str(exc)) from None
        self.node = options.node or wire.node_name_of(f"cfgplan_{robot}")
        type_name = wire.dds_type_name(wire.STRING)
        type_hash = wire.type_hash(wire.STRING)
        self.key_expr = wire.topic_key_expr(options.domain_id, options.topic, type_name, type_hash)
        self._zid = zid = str(session.zid())
        self.channels: dict[str, tuple[Any, bytes, int]] = {}
        """Each global channel's topic: its publisher, GID and next sequence number."""
        domain, space = options.domain_id, options.namespace
        self.node_token = wire.node_token(domain, zid, 0, self.node, namespace=space)
        self.publisher_token = wire.publisher_token(
            domain, zid, 0, 1, self.node, options.topic, type_name, type_hash, options.qos,
            namespace=space,
        )  # fmt: skip
        self.gid = wire.gid(self.publisher_token)
        self._session = session
        self._lock = threading.Lock()
        self.sequence_number = 1  # the next message's, from 1 as rmw_zenoh's publishers
        self.published = 0
        self.failed = 0
        try:
            self._tokens = [
                session.liveliness().declare_token(self.node_token),
                session.liveliness().declare_token(self.publisher_token),
            ]
            self._publisher = session.declare_publisher(self.key_expr)
        except Exception as exc:  # zenoh.ZError; zenoh is not imported here
            raise RunError(f"cannot declare the ROS 2 node {self.node}: {exc}") from None

    def __call__(self, event: Event) -> None:
        """A robot listener: publish ``event`` if it is one of the chosen
        Adaptation events, or a send on a global channel."""
        if isinstance(event, Adaptation) and event.what in self.options.events:
            self.publish(json.dumps(event.record(), sort_keys=True))
        elif (
            isinstance(event, Transfer)
            and event.direction == "send"
            and self.options.channels is not None
        ):
            self.publish_channel(event)

    def publish(self, text: str) -> None:
        """Put ``text`` as a ``std_msgs/msg/String`` on the events topic, with its attachment."""
        with self._lock:
            number = self.sequence_number
            self.sequence_number += 1
            self._put(self._publisher, self.gid, number, text)

    def _put(self, publisher: Any, gid: bytes, number: int, text: str) -> None:
        """With the lock held: ``text`` on ``publisher``, sequence number ``number``."""
        payload = wire.string_cdr(text)
        extra = wire.attachment(number, time.time_ns(), gid)
        try:
            publisher.put(payload, attachment=extra)
        except Exception:  # a closed session (the run is ending): counted, not raised
            self.failed += 1
            return
        self.published += 1

    def publish_channel(self, event: Transfer) -> None:
        """A send on a global channel as a message of the channel's topic
        (its publisher declared at the first)."""
        assert self.options.channels is not None
        topic = channel_topic(event.channel.data, self.options.channels)
        with self._lock:
            if topic not in self.channels:
                try:
                    self.channels[topic] = self._declare(topic)
                except Exception:  # a closed session, or a name zenoh refuses: counted
                    self.failed += 1
                    return
            publisher, gid, number = self.channels[topic]
            self.channels[topic] = (publisher, gid, number + 1)  # from 1 per publisher
            self._put(publisher, gid, number, json.dumps(event.record(), sort_keys=True))

    def _declare(self, topic: str) -> tuple[Any, bytes, int]:
        """The publisher of ``topic``, its GID and first sequence number, its
        ``MP`` token declared."""
        options, session = self.options, self._session
        wire.check_name(topic, "topic name")
        type_name, type_hash = wire.dds_type_name(wire.STRING), wire.type_hash(wire.STRING)
        token = wire.publisher_token(
            options.domain_id, self._zid, 0, 2 + len(self.channels), self.node, topic,
            type_name, type_hash, options.qos, namespace=options.namespace,
        )  # fmt: skip
        self._tokens.append(session.liveliness().declare_token(token))
        key = wire.topic_key_expr(options.domain_id, topic, type_name, type_hash)
        publisher = session.declare_publisher(key)
        self._tokens.append(publisher)
        return publisher, wire.gid(token), 1

    def close(self) -> None:
        """Withdraw the tokens and the publisher (closing the session does it too)."""
        if self._session.is_closed():
            return
        for declared in (*self._tokens, self._publisher):
            declared.undeclare()


def open_bridge(transport: object, robot: str, domain_id: int | None = None) -> EventBridge:
    """The bridge of ``robot`` on its Zenoh transport's session (``cfgplan run
    --robot NAME --ros2``), in the domain :func:`domain_id_of` gives."""
    session = getattr(transport, "session", None)
    if session is None:
        raise RunError("--ros2 publishes over the robot's Zenoh session: run it with --robot NAME")
    return EventBridge(session, robot, BridgeOptions(domain_id=domain_id_of(domain_id)))
