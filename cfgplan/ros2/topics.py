"""The ROS 2 topic map: which functionality input or output is which topic.

``cfgplan run ... --robot NAME --ros2-map FILE`` reads a TOML file of
``[[bind]]`` tables, each binding one port of one functionality of the domain
to a ROS 2 topic and message type::

    [[bind]]
    functionality = "camera"           # a functionality of the domain
    output = "image"                   # one of its :out descriptors (or input = ...)
    topic = "/scan"                    # an absolute ROS 2 topic name
    type = "sensor_msgs/msg/LaserScan" # a ROS 2 message type rosbags knows
    robot = "Pippi"                    # optional: only on this robot (default: any)
    timeout = 1.0                      # optional (an output): seconds without a
                                       # message before the sensor has failed
    reliability = "best_effort"        # optional QoS: reliable (default) or best_effort,
    durability = "volatile"            # volatile (default) or transient_local,
    depth = 5                          # keep last N (default 10)

* an **output** is read from the topic (``mode = "subscribe"``, its
  default): the value the functionality outputs there is the newest message,
  as a dict (:mod:`cfgplan.ros2.codec`); with ``mode = "publish"`` the value
  the functionality computes there is also published on the topic;
* an **input** is published on the topic (``mode = "publish"``, its
  default): each call puts the value the functionality receives there, a
  dict of the message's fields; with ``mode = "subscribe"`` the
  functionality receives the topic's newest message there instead of what
  its channel holds.

A port is named by its descriptor's predicate (``(image ?r)`` is ``image``).
Several ports of one functionality may share one message: ``output = ["pos",
"orient"]`` with ``fields = {pos = [...], orient = "..."}`` mapping each port
to fields of the message (:mod:`cfgplan.ros2.fields`); ``frame_id`` is the
``header.frame_id`` of the messages published.
:func:`load_map` checks the file against the domain and the state before
anything runs: an unknown functionality, port, robot, type or key is an
error naming the file and the line of its ``[[bind]]`` (or of the key).
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from cfgplan.ros2.fields import FieldMap, check_path
from cfgplan.ros2.rmw_zenoh import QoS
from cfgplan.runtime.errors import RunError

__all__ = ["DEFAULT_TIMEOUT", "Binding", "TopicMap", "load_map", "parse_map"]

DEFAULT_TIMEOUT = 1.0
"""Seconds a bound output's topic may be silent before its functionality has failed."""

KEYS = (
    "functionality", "input", "output", "mode", "topic", "type", "fields", "frame_id", "robot",
    "timeout", "reliability", "durability", "depth",
)  # fmt: skip
MODES = ("subscribe", "publish")
RELIABILITY = {"reliable": 1, "best_effort": 2}
"""The ``reliability`` of a binding's QoS, as rmw numbers it (rmw/types.h)."""
DURABILITY = {"volatile": 2, "transient_local": 1}
"""The ``durability`` of a binding's QoS, as rmw numbers it."""
DEFAULT_DEPTH = 10
"""A binding's history depth (keep last) unless ``depth`` says: rclcpp's and rclpy's default."""


@dataclass(frozen=True)
class Binding:
    """One port of one functionality bound to a topic."""

    functionality: str
    direction: Literal["input", "output"]
    ports: tuple[str, ...]
    indices: tuple[int, ...]
    """The ports' positions among the functionality's inputs (or outputs)."""
    topic: str
    msg_type: str
    robot: str | None = None
    timeout: float = DEFAULT_TIMEOUT
    objects: int = 0
    """The functionality's object arguments (after the robot)."""
    inputs: int = 0
    outputs: int = 0
    line: int | None = None
    mode: Literal["subscribe", "publish"] = "subscribe"
    """``subscribe``: the ports' values come from the topic; ``publish``: they go out on it."""
    fields: FieldMap | None = None
    """Which fields of the message each port is (``None``: one port, the whole message)."""
    frame_id: str = ""
    reliability: str = "reliable"
    durability: str = "volatile"
    depth: int = DEFAULT_DEPTH
    """The QoS of the binding's publisher or subscription (keep last ``depth``)."""

    @property
    def qos(self) -> QoS:
        """The binding's QoS in rmw's numbers (a token's QoS field; rclpy's profile)."""
        return QoS(RELIABILITY[self.reliability], DURABILITY[self.durability], 1, self.depth)

    @property
    def port(self) -> str:
        """The first (often only) port."""
        return self.ports[0]

    @property
    def index(self) -> int:
        return self.indices[0]

    def on(self, robot: str) -> bool:
        """Whether it applies where ``robot`` runs the functionality."""
        return self.robot is None or self.robot == robot


@dataclass(frozen=True)
class TopicMap:
    """The bindings of a map file."""

    bindings: tuple[Binding, ...]
    source: str = ""

    def of(self, robot: str) -> tuple[Binding, ...]:
        """The bindings that apply on ``robot``."""
        return tuple(b for b in self.bindings if b.on(robot))

    def implements(self, functionality: str, robot: str) -> bool:
        """Whether the map alone implements ``functionality`` on ``robot``: it is
        bound there and every one of its outputs is (an action's inputs
        published, a sensor's outputs read), so it needs no Python of its own."""
        mine = [b for b in self.of(robot) if b.functionality == functionality]
        if not mine:
            return False
        if mine[0].outputs == 0:  # an action: implemented if it publishes something
            return any(b.mode == "publish" for b in mine)
        read = {
            i for b in mine if (b.direction, b.mode) == ("output", "subscribe") for i in b.indices
        }
        return len(read) == mine[0].outputs


def _lines(text: str) -> list[int]:
    """The line of each ``[[bind]]`` header, in order."""
    return [
        n for n, line in enumerate(text.splitlines(), 1) if re.match(r"\s*\[\[\s*bind\s*\]\]", line)
    ]


def _key_line(text: str, start: int | None, key: str) -> int | None:
    """The line of ``key = ...`` in the table that starts at line ``start``."""
    if start is None:
        return None
    lines = text.splitlines()
    for n in range(start, len(lines)):  # 0-based: the lines after the header
        if re.match(r"\s*\[", lines[n]):
            break
        if re.match(rf"\s*{re.escape(key)}\s*=", lines[n]):
            return n + 1
    return start


def parse_map(text: str, source: str, domain: Any, agents: Sequence[str] = ()) -> TopicMap:
    """The bindings of map ``text`` (from file ``source``), checked against
    ``domain`` (a :class:`cfgplan.ir.model.Domain`) and the state's ``agents``."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line = re.search(r"line (\d+)", str(exc))
        raise RunError(
            f"the ROS 2 map is not TOML: {exc}",
            file=source,
            line=int(line[1]) if line else None,
        ) from None
    extra = sorted(set(data) - {"bind"})
    if extra:
        raise RunError(
            f"the ROS 2 map has {', '.join(extra)}: only [[bind]] tables",
            hint="docs/how-to/ros2.md, the topic map",
            file=source,
            line=1,
        )
    tables = data.get("bind", [])
    if not isinstance(tables, list):
        raise RunError("bind must be [[bind]] tables", file=source, line=1)
    starts = _lines(text)
    functionalities = {f.name.predicate: f for f in domain.functionalities}
    out: list[Binding] = []
    seen: dict[tuple[str, str, str, str | None], int | None] = {}
    for k, table in enumerate(tables):
        start = starts[k] if k < len(starts) else None

        def fail(
            message: str, key: str | None = None, hint: str | None = None, start: int | None = start
        ) -> RunError:
            line = start if key is None else _key_line(text, start, key)
            return RunError(message, hint=hint, file=source, line=line, column=1)

        if not isinstance(table, dict):  # bind = [1]: no [[bind]] header to point at
            raise RunError(
                f"[[bind]] entry {k + 1} is {table!r}, not a table of keys",
                file=source,
                line=_key_line(text, 0, "bind"),
                column=1,
            )
        unknown = sorted(set(table) - set(KEYS))
        if unknown:
            raise fail(
                f"[[bind]] has no key {unknown[0]} (its keys: {', '.join(KEYS)})", unknown[0]
            )
        for key in ("functionality", "topic", "type"):
            if not isinstance(table.get(key), str) or not table[key]:
                raise fail(f'[[bind]] needs {key} = "..."', key if key in table else None)
        name = table["functionality"]
        schema = functionalities.get(name)
        if schema is None:
            known = ", ".join(sorted(functionalities))
            raise fail(f"no functionality {name} in the domain (its: {known})", "functionality")
        given = [d for d in ("input", "output") if d in table]
        if len(given) != 1:
            raise fail('[[bind]] binds one port: give input = "..." or output = "..."')
        direction: Literal["input", "output"] = "input" if given[0] == "input" else "output"
        named = table[direction]
        chosen = [named] if isinstance(named, str) else named
        if (
            not isinstance(chosen, list)
            or not chosen
            or not all(isinstance(p, str) and p for p in chosen)
            or len(set(chosen)) != len(chosen)
        ):
            raise fail(f"{direction} is a port's name or a list of them: {named!r}", direction)
        ports = schema.inputs if direction == "input" else schema.outputs
        names = [p.predicate for p in ports]
        for port in chosen:
            if port not in names:
                have = ", ".join(names) or "none"
                raise fail(
                    f"{name} has no {direction} {port!r} (its {direction}s: {have})", direction
                )
        mode = table.get("mode", "publish" if direction == "input" else "subscribe")
        if mode not in MODES:
            raise fail(f"mode {mode!r} is not one of: {', '.join(MODES)}", "mode")
        if direction == "input" and mode == "publish" and schema.outputs:
            raise fail(
                f"{name} has outputs: only an action's inputs (a functionality without "
                "outputs) are published",
                direction,
            )
        topic, msg_type = table["topic"], table["type"]
        from cfgplan.ros2 import codec, rmw_zenoh

        try:
            rmw_zenoh.check_name(topic, "topic name")
            rmw_zenoh.dds_type_name(msg_type)
        except ValueError as exc:
            raise fail(str(exc), "topic" if msg_type.count("/") == 2 else "type") from None
        if not codec.known_type(msg_type):
            raise fail(
                f"unknown ROS 2 message type {msg_type} (rosbags's ROS 2 Jazzy types)", "type"
            )
        try:
            fields = _fields(table.get("fields"), tuple(chosen), msg_type)
        except ValueError as exc:
            raise fail(str(exc), "fields" if "fields" in table else direction) from None
        frame_id = table.get("frame_id", "")
        if not isinstance(frame_id, str):
            raise fail(f"frame_id {frame_id!r} is not a string", "frame_id")
        robot = table.get("robot")
        if robot is not None and (not isinstance(robot, str) or robot not in agents):
            raise fail(f"no robot {robot} in the state (its: {', '.join(agents)})", "robot")
        timeout = table.get("timeout", DEFAULT_TIMEOUT)
        if (
            isinstance(timeout, bool)
            or not isinstance(timeout, int | float)
            or not math.isfinite(timeout)
            or timeout <= 0
        ):
            raise fail(f"timeout {timeout!r} is not a number of seconds above 0", "timeout")
        qos: dict[str, Any] = {}
        for key, choices in (("reliability", RELIABILITY), ("durability", DURABILITY)):
            if key in table:
                if table[key] not in choices:
                    raise fail(f"{key} {table[key]!r} is not one of: {', '.join(choices)}", key)
                qos[key] = table[key]
        if "depth" in table:
            depth = table["depth"]
            if isinstance(depth, bool) or not isinstance(depth, int) or not 1 <= depth <= 10_000:
                raise fail(
                    f"depth {depth!r} is not a whole number of messages, 1 to 10000", "depth"
                )
            qos["depth"] = depth
        for port in chosen:
            bound = (name, direction, port, robot)
            if bound in seen:
                raise fail(
                    f"{name} {direction} {port} is bound twice (first at line {seen[bound]})"
                )
            seen[bound] = start
        out.append(
            Binding(
                name,
                direction,
                tuple(chosen),
                tuple(names.index(p) for p in chosen),
                topic,
                msg_type,
                robot,
                float(timeout),
                len(schema.name.args) - 1,
                len(schema.inputs),
                len(schema.outputs),
                start,
                mode,
                fields,
                frame_id,
                **qos,
            )
        )
    return TopicMap(tuple(out), source)


def _fields(given: Any, ports: tuple[str, ...], msg_type: str) -> FieldMap | None:
    """The ``fields`` table of a binding of ``ports``, checked (``ValueError``)."""
    if given is None:
        if len(ports) > 1:
            raise ValueError(
                f"{len(ports)} ports in one {msg_type}: give fields = {{{ports[0]} = "
                '"field.path", ...}, the field of the message each port is'
            )
        return None
    if not isinstance(given, dict):
        raise ValueError(f'fields is a table {{port = "field.path", ...}}, not {given!r}')
    if set(given) != set(ports):
        raise ValueError(
            f"fields names the ports {', '.join(sorted(given)) or 'none'}: give exactly "
            f"{', '.join(ports)}"
        )
    paths: list[tuple[str, ...] | str] = []
    for port in ports:
        path = given[port]
        if isinstance(path, str):
            paths.append(check_path(msg_type, path))
        elif isinstance(path, list) and path and all(isinstance(p, str) for p in path):
            paths.append(tuple(check_path(msg_type, p) for p in path))
        else:
            raise ValueError(f"fields.{port} is a field path or a list of them, not {path!r}")
    return FieldMap(ports, tuple(paths))


def load_map(path: str | Path, domain: Any, agents: Sequence[str] = ()) -> TopicMap:
    """:func:`parse_map` of the file ``path``."""
    try:
        text = Path(path).read_text("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise RunError(f"cannot read the ROS 2 map {path}: {exc}") from None
    return parse_map(text, str(path), domain, agents)
