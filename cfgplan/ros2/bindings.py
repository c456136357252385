"""Functionalities whose inputs or outputs are ROS 2 topics, over rmw_zenoh (issue 36).

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
  rmw_zenoh's attachment.

:meth:`TopicBindings.registry` returns the implementations with the bound
functionalities wrapped: a functionality whose every output is bound needs no
implementation of its own; otherwise its implementation runs and the bound
outputs replace what it returns.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from cfgplan.ros2 import codec
from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.ros2.topics import Binding, TopicMap
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.faults import ResourceFailure
from cfgplan.runtime.registry import Implementation, Registry
from cfgplan.runtime.values import MAX_VALUE_BYTES

__all__ = ["Latest", "TopicBindings", "open_bindings"]

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


class TopicBindings:
    """One robot's bound topics on its Zenoh session (see the module)."""

    def __init__(
        self,
        session: Any,
        robot: str,
        bindings: TopicMap,
        domain_id: int = 0,
        max_bytes: int = MAX_VALUE_BYTES,
    ) -> None:
        self.max_bytes = max_bytes
        """A bound topic's message over this many bytes is dropped unread (0: no limit)."""
        self.robot = robot
        self.bindings = bindings.of(robot)
        self.node = wire.node_name_of(f"cfgplan_{robot}_topics")
        self.domain_id = domain_id
        self.latest: dict[Binding, Latest] = {}
        self.published: dict[Binding, int] = {}
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
                if binding.direction == "output":
                    self._token(wire.subscriber_token(*fields, hash_))
                    key = wire.topic_key_expr(domain_id, binding.topic, type_name, "*")
                    latest = self.latest[binding] = Latest()
                    self._declared.append(
                        session.declare_subscriber(key, self._receiver(binding, latest))
                    )
                else:
                    token = wire.publisher_token(*fields, hash_)
                    self._token(token)
                    key = wire.topic_key_expr(domain_id, binding.topic, type_name, hash_)
                    publisher = session.declare_publisher(key)
                    self._declared.append(publisher)
                    self._publishers[binding] = (publisher, wire.gid(token))
                    self.published[binding] = 0
        except RunError:
            raise
        except Exception as exc:  # zenoh.ZError; zenoh is not imported here
            raise RunError(f"cannot declare the ROS 2 node {self.node}: {exc}") from None

    def _token(self, token: str) -> None:
        self._declared.append(self._session.liveliness().declare_token(token))

    def _receiver(self, binding: Binding, latest: Latest) -> Callable[[Any], None]:
        def receive(sample: Any) -> None:  # on Zenoh's thread: no decoding here
            payload = sample.payload
            if self.max_bytes and len(payload) > self.max_bytes:
                latest.oversized += 1
                return
            latest.raw, latest.at = payload.to_bytes(), time.monotonic()
            latest.received += 1

        return receive

    def publish(self, binding: Binding, value: Any) -> None:
        """Put ``value`` on the binding's topic as its message type (``ValueError``
        if it does not fit the type: the action's call fails, saying why)."""
        payload = codec.cdr_of_value(binding.msg_type, value)
        publisher, gid = self._publishers[binding]
        with self._lock:
            number = self._sequence
            self._sequence += 1
        publisher.put(payload, attachment=wire.attachment(number, time.time_ns(), gid))
        self.published[binding] += 1

    def implementation(self, name: str, base: Implementation | None) -> Implementation | None:
        """``base`` with this robot's bindings of functionality ``name`` (``None``
        when it has none: ``base`` as it is)."""
        mine = [b for b in self.bindings if b.functionality == name]
        if not mine:
            return base
        outputs = [b for b in mine if b.direction == "output"]
        inputs = [b for b in mine if b.direction == "input"]
        first = mine[0]
        if base is None and len(outputs) < first.outputs:
            return None  # some outputs need an implementation: the registry says which
        count = first.outputs

        def bound(*args: Any) -> Any:
            values = args[first.objects :]
            for binding in inputs:
                self.publish(binding, values[binding.index])
            result = None if base is None else base(*args)
            if not count:
                return result
            outs: list[Any]
            if count == 1:
                outs = [result]
            elif result is None:
                outs = [None] * count
            else:
                outs = list(result)  # type: ignore[call-overload]
            for binding in outputs:
                outs[binding.index] = self.latest[binding].read(binding)
            return outs[0] if count == 1 else tuple(outs)

        return Implementation(
            name,
            bound,
            None if base is None else base.precondition,
            None if base is None else base.stop,
        )

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
