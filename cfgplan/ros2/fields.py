"""Ports to message fields and back: one ROS 2 message carrying several ports.

A ``[[bind]]`` of the topic map (:mod:`cfgplan.ros2.topics`) may bind several
ports of one functionality to one message, each to a field of it::

    output = ["pos", "orient"]
    fields = { pos = ["pose.position.x", "pose.position.y"], orient = "pose.orientation.yaw" }

A port's **path** is a dotted field path of the message type: a number or
string field (the port holds that value), a nested message (the port holds a
dict of its fields), or ``<quaternion>.yaw`` for a ``geometry_msgs/msg/Quaternion``
(the port holds an angle in radians about z; the quaternion is
``(0, 0, sin(yaw/2), cos(yaw/2))``, and a quaternion read is turned back into
its yaw). A **list** of paths means the port holds a list, its items those
fields in order (a position ``[x, y]``).

Publishing, the fields no port sets are zero (:mod:`cfgplan.ros2.codec`),
except a top-level ``header`` (``std_msgs/msg/Header``) no port sets: its
``stamp`` is the time of publishing and its ``frame_id`` the binding's
``frame_id``, as a ROS 2 driver stamps its messages.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from cfgplan.ros2.rmw_zenoh import NAME, _typestore

__all__ = ["QUATERNION", "FieldMap", "check_path", "message_of_ports", "ports_of_message"]

QUATERNION = "geometry_msgs/msg/Quaternion"
HEADER = "std_msgs/msg/Header"
YAW = "yaw"


@dataclass(frozen=True)
class FieldMap:
    """Which fields of the message each bound port is, in the binding's port order."""

    ports: tuple[str, ...]
    paths: tuple[tuple[str, ...] | str, ...]
    """Per port: one path (the port is that field), or a tuple (the port is a list)."""

    def sets(self, name: str) -> bool:
        """Whether a port sets the top-level field ``name``."""
        flat = [p for path in self.paths for p in ((path,) if isinstance(path, str) else path)]
        return any(p.split(".")[0] == name for p in flat)


def check_path(msg_type: str, path: str) -> str:
    """``path`` if it names a field of ``msg_type`` (or ``.yaw`` of a
    quaternion in it), else ``ValueError`` naming the fields there are."""
    store = _typestore()
    current: str | None = msg_type
    parts = path.split(".")
    for n, name in enumerate(parts):
        if current is None:
            raise ValueError(f"{'.'.join(parts[:n])} of {msg_type} has no fields ({path!r})")
        if name == YAW and current == QUATERNION and n == len(parts) - 1:
            return path
        _, fields = store.fielddefs[current]
        found = dict(fields).get(name)
        if found is None:
            names = [f for f, _ in fields] + ([YAW] if current == QUATERNION else [])
            where = ".".join(parts[:n]) or msg_type
            raise ValueError(f"{where} has no field {name!r} (its fields: {', '.join(names)})")
        kind, desc = found
        current = desc if kind == NAME else None
    return path


def _set(message: dict[str, Any], path: str, value: Any) -> None:
    *head, last = path.split(".")
    for name in head:
        message = message.setdefault(name, {})
    if last == YAW:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{path}: {value!r} is not an angle in radians")
        message.update(x=0.0, y=0.0, z=math.sin(value / 2), w=math.cos(value / 2))
    else:
        message[last] = value


def _get(message: Mapping[str, Any], path: str) -> Any:
    *head, last = path.split(".")
    for name in head:
        message = message[name]
    if last == YAW:
        x, y, z, w = (float(message[k]) for k in "xyzw")
        return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return message[last]


def message_of_ports(
    msg_type: str, fields: FieldMap, values: Sequence[Any], stamp_ns: int, frame_id: str = ""
) -> dict[str, Any]:
    """The message (a dict of fields, for :func:`cfgplan.ros2.codec.cdr_of_value`)
    that holds the ports' ``values``; ``ValueError`` naming the port whose
    value does not fit."""
    message: dict[str, Any] = {}
    for port, path, value in zip(fields.ports, fields.paths, values, strict=True):
        if isinstance(path, str):
            _set(message, path, value)
            continue
        if not isinstance(value, list | tuple) or len(value) != len(path):
            raise ValueError(f"port {port}: {value!r} is not a list of {len(path)} values")
        for item, one in zip(value, path, strict=True):
            _set(message, one, item)
    _, top = _typestore().fielddefs[msg_type]
    if dict(top).get("header") == (NAME, HEADER) and not fields.sets("header"):
        sec, nanosec = divmod(stamp_ns, 10**9)
        message["header"] = {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame_id}
    return message


def ports_of_message(fields: FieldMap, message: Mapping[str, Any]) -> list[Any]:
    """The ports' values in ``message`` (a decoded dict), in the map's port order."""
    out: list[Any] = []
    for path in fields.paths:
        if isinstance(path, str):
            out.append(_get(message, path))
        else:
            out.append([_get(message, one) for one in path])
    return out
