"""``cfgplan run ... --foxglove [HOST:]PORT``: the run served to Foxglove live.

The foxglove-sdk's WebSocket server (``foxglove.start_server``, the Foxglove
WebSocket protocol) on its own context, so that nothing else this process
logs reaches it. What a client sees:

* **channels** — each event of the robots of this process as one JSON
  message on the topic :mod:`cfgplan.record.channels` names, with the same
  JSON Schema as in an MCAP recording: ``/cfgplan/switches``,
  ``/cfgplan/failures``, ``/cfgplan/ROBOT/freshness`` (stale and fresh
  inputs, 3.2), ``/cfgplan/ROBOT/calls`` and the rest. The society's
  channels and each robot's of this process are advertised from the start
  (a switch can be subscribed to before it happens), a global channel's
  ``sent`` and ``received`` when its first value comes; messages are sent
  only to the clients that subscribe (the SDK drops the oldest for a slow
  client);
* **the connection graph** (capability ``connectionGraph``, Foxglove's *Topic
  Graph* panel) — the running configuration: each functionality a node
  (``F7: camera(Pippi)``), each of its channels (5.2.2) a topic
  ``/cfgplan/channels/CHANNEL`` published by its source and subscribed by its
  target; each robot a node publishing its own topics above, the coordinator
  those of the society. After a switch (5.5) the graph is the new
  configuration's, as the coordinator's reconfigurator holds it; when it
  stops (no configuration), it has no functionality. A robot that takes
  over coordination publishes the society's topics from then on, and its
  graph follows its switches; one that steps down keeps the last.

Only this module imports ``foxglove``, and only when ``--foxglove`` is given.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import foxglove
from foxglove.websocket import Capability, WebSocketServer
from pydantic import BaseModel

from cfgplan.configuration.model import Configuration
from cfgplan.live.address import Address
from cfgplan.record.channels import (
    MESSAGE_ENCODING,
    SCHEMA_ENCODING,
    TOPICS,
    Entry,
    entry_of,
    schema_name,
    schema_of,
    segment,
)
from cfgplan.record.policy import Policy
from cfgplan.runtime.events import Adaptation, Event
from cfgplan.runtime.tracefile import elided
from cfgplan.runtime.transport import ChannelKey

__all__ = ["FoxgloveLive", "Graph", "graph_of", "serve"]

CHANNELS = "/cfgplan/channels/"
"""Where the configuration's channels are in the connection graph."""
REDRAWN = frozenset({"switch", "no-configuration", "takeover", "step-down"})
"""Events after which the graph is drawn again: the configuration, or who
coordinates, changed."""


@dataclass
class Graph:
    """A connection graph as plain data: topic -> publisher ids, topic -> subscriber ids."""

    published: dict[str, list[str]] = field(default_factory=dict)
    subscribed: dict[str, list[str]] = field(default_factory=dict)

    def publish(self, topic: str, node: str) -> None:
        nodes = self.published.setdefault(topic, [])
        if node not in nodes:
            nodes.append(node)

    def subscribe(self, topic: str, node: str) -> None:
        nodes = self.subscribed.setdefault(topic, [])
        if node not in nodes:
            nodes.append(node)

    def sdk(self) -> foxglove.ConnectionGraph:
        graph = foxglove.ConnectionGraph()
        for topic, nodes in self.published.items():
            graph.set_published_topic(topic, nodes)
        for topic, nodes in self.subscribed.items():
            graph.set_subscribed_topic(topic, nodes)
        return graph


def graph_of(config: Configuration | None) -> Graph:
    """The functionalities and channels of ``config`` (none: nothing runs)."""
    graph = Graph()
    if config is None:
        return graph
    nodes = {f.label: str(f) for f in config.functionalities}
    for c in config.channels:
        topic = CHANNELS + segment(str(ChannelKey(c.source, c.target, c.data)))
        graph.publish(topic, nodes.get(c.source, c.source))
        graph.subscribe(topic, nodes.get(c.target, c.target))
    return graph


class FoxgloveLive:
    """The server, its channels and graph; a listener of the society."""

    def __init__(
        self,
        server: WebSocketServer,
        context: foxglove.Context,
        config: Configuration | None,
        robots: Sequence[str] = (),
        lead: str = "cfgplan",
        running: Callable[[], Configuration | None] | None = None,
        policy: Policy | None = None,
    ) -> None:
        self.server = server
        self.port = server.port
        self.policy = policy or Policy()
        self._context = context
        self._running = running
        self._config = config
        self._channels: dict[str, foxglove.Channel] = {}
        self._topics: dict[str, str] = {}  # topic -> the robot that publishes it
        self._society: set[str] = set()  # the society's topics, the coordinator's
        self._lock = threading.Lock()
        self.refused = 0
        for model, template in TOPICS.items():  # advertised ahead
            if "{channel}" in template:
                continue
            if "{robot}" not in template:
                self._open(template, model, (), lead)
                self._society.add(template)
            for robot in robots if "{robot}" in template else ():
                topic = template.format(robot=segment(robot))
                self._open(topic, model, (("robot", robot),), robot)
        self.graph = self._graph()
        self.server.publish_connection_graph(self.graph.sdk())

    def __call__(self, event: Event) -> None:
        """A robot's event: sent on its channel; a switch redraws the graph."""
        try:
            obj = elided(event, self.policy.elide).record()
            data = json.dumps(obj, separators=(",", ":")).encode()
            e = entry_of(obj, data)
        except Exception:  # the robots must not stop for a viewer
            self.refused += 1
            return
        with self._lock:
            self._log(e)
            if isinstance(event, Adaptation) and event.what in REDRAWN:
                self._switched(event)

    def _log(self, e: Entry) -> None:
        channel = self._channels.get(e.topic)
        if channel is None:
            channel = self._open(e.topic, e.model, e.metadata, e.robot)
            self.graph.publish(e.topic, e.robot)
            self.server.publish_connection_graph(self.graph.sdk())
        channel.log(e.data, log_time=e.log_time)

    def _open(
        self,
        topic: str,
        model: type[BaseModel],
        metadata: tuple[tuple[str, str], ...],
        robot: str,
    ) -> foxglove.Channel:
        schema = foxglove.Schema(
            name=schema_name(model), encoding=SCHEMA_ENCODING, data=schema_of(model)
        )
        channel = foxglove.Channel(
            topic,
            schema=schema,
            message_encoding=MESSAGE_ENCODING,
            context=self._context,
            metadata=dict(metadata),
        )
        self._channels[topic] = channel
        self._topics[topic] = robot
        return channel

    def _switched(self, event: Adaptation) -> None:
        """The configuration changed (or who coordinates): the graph again."""
        lead = {"takeover": event.robot, "step-down": event.field("leader")}.get(event.what)
        if isinstance(lead, str):  # the society's topics are the new coordinator's
            for topic in self._society:
                self._topics[topic] = lead
        if self._running is not None:
            self._config = self._running()
        self.graph = self._graph()
        self.server.publish_connection_graph(self.graph.sdk())

    def _graph(self) -> Graph:
        graph = graph_of(self._config)
        for topic, robot in self._topics.items():
            graph.publish(topic, robot)
        return graph

    def stop(self) -> None:
        """Stop the server (its clients are disconnected)."""
        with self._lock:
            for channel in self._channels.values():
                channel.close()
        self.server.stop()


def serve(
    address: Address,
    title: str,
    config: Configuration,
    robots: Sequence[str] = (),
    lead: str = "cfgplan",
    running: Callable[[], Configuration | None] | None = None,
    policy: Policy | None = None,
) -> FoxgloveLive:
    """Start the server at ``address`` (port 0: any free one); ``OSError``-like
    errors of the SDK propagate (the caller says them)."""
    context = foxglove.Context()
    server = foxglove.start_server(
        name=f"cfgplan: {title}",
        host=address.host,
        port=address.port,
        capabilities=[Capability.ConnectionGraph],
        context=context,
    )
    return FoxgloveLive(server, context, config, robots, lead, running, policy)
