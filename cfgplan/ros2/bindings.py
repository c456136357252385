"""Functionalities whose inputs or outputs are ROS 2 topics, over rmw_zenoh.

:class:`TopicBindings` puts the bindings of a map (:mod:`cfgplan.ros2.topics`)
that apply on one robot on that robot's Zenoh session, as one ROS 2 node,
``/cfgplan_<robot>_topics`` (its ``NN`` token):

* a bound **output** is a subscriber (an ``MS`` token) on the topic's key
  expression ``<domain>/<topic>/<dds type>/*`` (any type hash: rmw_zenoh
  releases before Jazzy write none); it keeps the newest message, decoded to
  a dict (:mod:`cfgplan.ros2.codec`). The functionality outputs it there; no
  message yet is "no data" (``None``) for the binding's ``timeout``; a topic
  silent for longer is the sensor failing: the call raises
  :class:`~cfgplan.runtime.faults.ResourceFailure`, the monitor reports the
  failure as for any stalled sensor (5.5), probes it, and reports the
  recovery once messages flow again;
* a bound **input** of an action is a publisher (an ``MP`` token) on the
  topic's key expression with the type's RIHS01 hash; every call publishes the
  value the action receives there, encoded as the message type, with
  rmw_zenoh's attachment;
* a **published output** (``mode = "publish"``) is a publisher too: every
  call that computes the output (not "no data") publishes it, and the value
  goes on to the functionality's channels as usual;
* a **subscribed input** (``mode = "subscribe"``) is a subscriber: the
  functionality receives the topic's newest message there instead of its
  channel's value; no message yet, the call does nothing (no data to act
  on); a topic silent for longer than the timeout fails the call, as for
  an output.

Several ports may share one message (:mod:`cfgplan.ros2.fields`).

:meth:`TopicBindings.registry` returns the implementations with the bound
functionalities wrapped: a functionality whose every output is bound needs no
implementation of its own; otherwise its implementation runs and the bound
outputs replace what it returns.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from cfgplan.ros2 import codec
from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.ros2.fields import message_of_ports, ports_of_message
from cfgplan.ros2.topics import Binding, TopicMap
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.faults import ResourceFailure
from cfgplan.runtime.outputs import split
from cfgplan.runtime.registry import Implementation, Registry
from cfgplan.runtime.values import MAX_VALUE_BYTES

__all__ = ["Bindings", "Latest", "TopicBindings", "open_bindings"]

NODE_ID = 1
"""The node id of the bindings' node (the events bridge's node is 0)."""


@dataclass
class Latest:
    """The newest message of a subscribed topic, and when it came."""

    since: float = field(default_factory=time.monotonic)
    raw: bytes | None = None
    """The newest payload, kept as it came: decoded only when read (a flood of
    messages costs a copy each, not a decoding)."""
    at: float | None = None
    received: int = 0
    undecodable: int = 0
    oversized: int = 0
    _decoded: tuple[bytes, Any] | None = None  # the last payload decoded, and its value
    _bad: bytes | None = None  # the last payload that could not be

    def read(self, binding: Binding, now: float | None = None) -> Any:
        """The newest message, ``None`` while none came (or none could be
        decoded) within the timeout of the start, :class:`ResourceFailure` once
        the topic is silent for longer."""
        now = time.monotonic() if now is None else now
        last = self.since if self.at is None else self.at
        if now - last > binding.timeout:
            what = "no message yet" if self.at is None else "no message"
            raise ResourceFailure(
                f"topic {binding.topic} ({binding.msg_type}): {what} for {now - last:.1f} s "
                f"(timeout {binding.timeout:g} s)"
            )
        raw = self.raw
        kept = None if self._decoded is None else self._decoded[1]
        if raw is None or raw is self._bad:
            return kept
        if self._decoded is not None and self._decoded[0] is raw:
            return kept
        try:
            self._decoded = (raw, codec.value_of_cdr(binding.msg_type, raw))
        except Exception:  # a payload of another type or layout: counted, not kept
            self.undecodable += 1
            self._bad = raw
            return kept
        return self._decoded[1]


class Bindings:
    """One robot's bound topics, whatever carries them (see the module): the
    newest message of each subscription, the messages published, and the
    functionalities wrapped. :class:`TopicBindings` puts them on the robot's
    Zenoh session (the rmw_zenoh layout), :class:`cfgplan.ros2.node.RclpyBindings`
    on an rclpy node; each gives :meth:`_send` and calls :meth:`_received`."""

    def __init__(self, robot: str, bindings: TopicMap, max_bytes: int = MAX_VALUE_BYTES) -> None:
        self.max_bytes = max_bytes
        """A bound topic's message over this many bytes is dropped unread (0: no limit)."""
        self.robot = robot
        self.bindings = bindings.of(robot)
        self.latest: dict[Binding, Latest] = {}
        self.published: dict[Binding, int] = {}
        self.delivered: dict[Binding, int] = {}
        """Per subscribed input: the calls that received the topic's message."""
        for binding in self.bindings:
            if binding.mode == "subscribe":
                self.latest[binding] = Latest()
                self.delivered[binding] = 0
            else:
                self.published[binding] = 0

    def _received(self, latest: Latest, size: int, payload: Callable[[], bytes]) -> None:
        """A message of ``size`` bytes came (on the middleware's thread: no decoding here)."""
        if self.max_bytes and size > self.max_bytes:
            latest.oversized += 1
            return
        latest.raw, latest.at = payload(), time.monotonic()
        latest.received += 1

    def _send(self, binding: Binding, payload: bytes) -> None:
        """Put a CDR ``payload`` (its header included) on the binding's topic."""
        raise NotImplementedError

    def _now_ns(self) -> int:
        """The stamp of a message published now, ns (a ROS node's clock: sim time too)."""
        return time.time_ns()

    def publish(self, binding: Binding, values: Sequence[Any]) -> None:
        """Put the binding's port ``values`` on its topic as its message type
        (``ValueError`` if they do not fit the type: the call fails, saying why)."""
        if binding.fields is None:
            message = values[0]
        else:
            stamp = self._now_ns()
            message = message_of_ports(
                binding.msg_type, binding.fields, values, stamp, binding.frame_id
            )
        self._send(binding, codec.cdr_of_value(binding.msg_type, message))
        self.published[binding] += 1

    def read(self, binding: Binding) -> list[Any] | None:
        """The binding's port values in the topic's newest message (``None``: no
        message yet; :class:`ResourceFailure`: the topic silent too long)."""
        message = self.latest[binding].read(binding)
        if message is None:
            return None
        if binding.fields is None:
            return [message]
        return ports_of_message(binding.fields, message)

    def implementation(self, name: str, base: Implementation | None) -> Implementation | None:
        """``base`` with this robot's bindings of functionality ``name`` (``None``
        when it has none: ``base`` as it is)."""
        mine = [b for b in self.bindings if b.functionality == name]
        if not mine:
            return base

        def of(direction: str, mode: str) -> list[Binding]:
            return [b for b in mine if (b.direction, b.mode) == (direction, mode)]

        read, computed = of("output", "subscribe"), of("output", "publish")
        sent, taken = of("input", "publish"), of("input", "subscribe")
        first = mine[0]
        count = first.outputs
        if base is None and (
            len({i for b in read for i in b.indices}) < count or (not count and not sent)
        ):
            return None  # some outputs need an implementation: the registry says which

        def bound(*given: Any) -> Any:
            args = list(given)
            for binding in taken:
                got = self.read(binding)
                if got is None:
                    return None  # no message yet: nothing to act on
                for index, value in zip(binding.indices, got, strict=True):
                    args[first.objects + index] = value
                self.delivered[binding] += 1
            values = args[first.objects :]
            for binding in sent:
                self.publish(binding, [values[i] for i in binding.indices])
            result = None if base is None else base(*args)
            if not count:
                return result
            outs: list[Any] = split(result, count)  # a RunError for a wrong shape
            for binding in computed:
                port_values = [outs[i] for i in binding.indices]
                if all(v is not None for v in port_values):
                    self.publish(binding, port_values)
            for binding in read:
                got = self.read(binding) or [None] * len(binding.indices)
                for index, value in zip(binding.indices, got, strict=True):
                    outs[index] = value
            return outs[0] if count == 1 else tuple(outs)

        return Implementation(
            name,
            bound,
            None if base is None else base.precondition,
            None if base is None else base.stop,
        )

    def summary(self) -> list[str]:
        """One line per binding: the messages it received or published."""
        lines = []
        for b in self.bindings:
            what = f"{self.robot} {b.topic} ({b.msg_type}), {b.functionality} {', '.join(b.ports)}"
            if b.mode == "publish":
                lines.append(f"{what}: {self.published[b]} messages published")
                continue
            got = f"{what}: {self.latest[b].received} messages received"
            if b.direction == "input":
                got += f", given to {self.delivered[b]} calls"
            lines.append(got)
        return lines

    def registry(self, base: Registry) -> Registry:
        """``base``'s implementations, the bound functionalities wrapped."""
        names = sorted({*base.names(), *(b.functionality for b in self.bindings)})
        found = []
        for name in names:
            impl = self.implementation(name, base.lookup(name) if name in base else None)
            if impl is not None:
                found.append(impl)
        return Registry(found, source=base.source)

    def close(self) -> None:
        """Withdraw what was declared."""


class TopicBindings(Bindings):
    """One robot's bound topics on its Zenoh session, in rmw_zenoh's layout."""

    def __init__(
        self,
        session: Any,
        robot: str,
        bindings: TopicMap,
        domain_id: int = 0,
        max_bytes: int = MAX_VALUE_BYTES,
    ) -> None:
        super().__init__(robot, bindings, max_bytes)
        self.node = wire.node_name_of(f"cfgplan_{robot}_topics")
        self.domain_id = domain_id
        self._session = session
        self._lock = threading.Lock()
        self._declared: list[Any] = []
        self._publishers: dict[Binding, tuple[Any, bytes]] = {}
        self._sequence = 1
        zid = str(session.zid())
        try:
            self._token(wire.node_token(domain_id, zid, NODE_ID, self.node))
            for entity, binding in enumerate(self.bindings, start=1):
                type_name = wire.dds_type_name(binding.msg_type)
                hash_ = wire.type_hash(binding.msg_type)
                fields = (domain_id, zid, NODE_ID, entity, self.node, binding.topic, type_name)
                qos = binding.qos
                if binding.mode == "subscribe":
                    self._token(wire.subscriber_token(*fields, hash_, qos))
                    key = wire.topic_key_expr(domain_id, binding.topic, type_name, "*")
                    self._declared.append(
                        session.declare_subscriber(key, self._receiver(self.latest[binding]))
                    )
                else:
                    token = wire.publisher_token(*fields, hash_, qos)
                    self._token(token)
                    key = wire.topic_key_expr(domain_id, binding.topic, type_name, hash_)
                    publisher = session.declare_publisher(key)
                    self._declared.append(publisher)
                    self._publishers[binding] = (publisher, wire.gid(token))
        except RunError:
            raise
        except Exception as exc:  # zenoh.ZError; zenoh is not imported here
            raise RunError(f"cannot declare the ROS 2 node {self.node}: {exc}") from None

    def _token(self, token: str) -> None:
        self._declared.append(self._session.liveliness().declare_token(token))

    def _receiver(self, latest: Latest) -> Callable[[Any], None]:
        def receive(sample: Any) -> None:  # on Zenoh's thread
            payload = sample.payload
            self._received(latest, len(payload), payload.to_bytes)

        return receive

    def _send(self, binding: Binding, payload: bytes) -> None:
        publisher, gid = self._publishers[binding]
        with self._lock:
            number = self._sequence
            self._sequence += 1
        publisher.put(payload, attachment=wire.attachment(number, time.time_ns(), gid))

    def close(self) -> None:
        """Withdraw the tokens, subscribers and publishers (closing the session does too)."""
        if self._session.is_closed():
            return
        for declared in self._declared:
            declared.undeclare()


def open_bindings(
    transport: object,
    robot: str,
    bindings: TopicMap,
    domain_id: int | None = None,
    max_bytes: int = MAX_VALUE_BYTES,
) -> TopicBindings:
    """The bindings of ``robot`` on its Zenoh transport's session (``cfgplan run
    --robot NAME --ros2-map FILE``), in the ROS domain of
    :func:`cfgplan.ros2.bridge.domain_id_of`; a message over ``max_bytes``
    (``--max-value-bytes``; 0: no limit) is dropped unread."""
    from cfgplan.ros2.bridge import domain_id_of

    session = getattr(transport, "session", None)
    if session is None:
        raise RunError("--ros2-map binds topics on the robot's Zenoh session: give --robot NAME")
    return TopicBindings(session, robot, bindings, domain_id_of(domain_id), max_bytes)
