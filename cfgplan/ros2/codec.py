"""ROS 2 messages as plain values: CDR bytes to a dict and back.

A functionality bound to a ROS 2 topic (:mod:`cfgplan.ros2.topics`) sees a
message as the value of one of its inputs or outputs: a dict of the
message's fields, nested messages as dicts, arrays and sequences as lists,
numbers and strings as themselves (:func:`value_of_cdr`). The same dict, with
any field left out taking its zero value (0, 0.0, ``""``, ``False``, an empty
sequence, a zero message), is what an action's input must hold to be
published (:func:`cdr_of_value`). Values cross global channels as JSON, so a
message read on one robot can be used on another.

CDR is rosbags's (``serialize_cdr``/``deserialize_cdr``), with the 4-byte
encapsulation header rmw_zenoh puts before every payload (design.md,
"Serialization/Deserialization"); the message definitions are rosbags's ROS 2
Jazzy ones (:func:`cfgplan.ros2.rmw_zenoh.type_hash` uses the same).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from cfgplan.ros2.rmw_zenoh import (
    ARRAY,
    EMPTY_MEMBER,
    NAME,
    SEQUENCE,
    _typestore,
    decode_cdr,
)

__all__ = ["cdr_of_value", "known_type", "message_of_value", "value_of_cdr", "value_of_message"]

_NUMPY = {
    "bool": "bool",
    "byte": "uint8",
    "char": "uint8",
    "octet": "uint8",
    "int8": "int8",
    "uint8": "uint8",
    "int16": "int16",
    "uint16": "uint16",
    "int32": "int32",
    "uint32": "uint32",
    "int64": "int64",
    "uint64": "uint64",
    "float32": "float32",
    "float64": "float64",
}
"""The numpy dtype rosbags keeps an array or sequence of each base type in."""


def known_type(msg_type: str) -> bool:
    """Whether rosbags knows the message type ``pkg/msg/Name``."""
    return msg_type in _typestore().fielddefs


def _zero(base: str) -> Any:
    if base in ("string", "wstring"):
        return ""
    if base == "bool":
        return False
    if base in ("float32", "float64"):
        return 0.0
    return 0


def _base(value: Any, base: str, where: str) -> Any:
    if base in ("string", "wstring"):
        if not isinstance(value, str):
            raise ValueError(f"{where}: {value!r} is not a string")
        return value
    if base == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{where}: {value!r} is not true or false")
        return value
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{where}: {value!r} is not a number")
    if base in ("float32", "float64"):
        return float(value)
    if isinstance(value, float) and not value.is_integer():
        raise ValueError(f"{where}: {value!r} is not a whole number ({base})")
    return int(value)


def _field(node: tuple[int, Any], value: Any, where: str) -> Any:
    """One field's value as rosbags holds it, from the plain value (``None``: zero)."""
    kind, desc = node
    if kind == NAME:
        return message_of_value(desc, {} if value is None else value, where)
    if kind in (ARRAY, SEQUENCE):
        element, size = desc
        items = [] if value is None else value
        if not isinstance(items, list | tuple):
            raise ValueError(f"{where}: {items!r} is not a list")
        if kind == ARRAY and value is not None and len(items) != size:
            raise ValueError(f"{where}: {len(items)} items, not {size}")
        if kind == ARRAY and value is None:
            items = [None] * size
        if element[0] == 1 and element[1][0] in _NUMPY:
            import numpy

            base = element[1][0]
            checked = [_base(_zero(base) if v is None else v, base, where) for v in items]
            return numpy.array(checked, dtype=_NUMPY[base])
        return [_field(element, v, f"{where}[{i}]") for i, v in enumerate(items)]
    base = desc[0]
    return _zero(base) if value is None else _base(value, base, where)


def message_of_value(msg_type: str, value: Any, where: str = "") -> Any:
    """The rosbags message of type ``msg_type`` holding the dict ``value``;
    ``ValueError`` saying which field is wrong (or unknown)."""
    store = _typestore()
    where = where or msg_type
    if not isinstance(value, Mapping):
        raise ValueError(f"{where}: {value!r} is not a {msg_type} (a dict of its fields)")
    _, fields = store.fielddefs[msg_type]
    names = [name for name, _ in fields]
    unknown = sorted(set(value) - set(names))
    if unknown:
        raise ValueError(
            f"{where}: {msg_type} has no field {', '.join(map(str, unknown))} "
            f"(its fields: {', '.join(names)})"
        )
    given = {name: _field(node, value.get(name), f"{where}.{name}") for name, node in fields}
    return store.types[msg_type](**given)


def cdr_of_value(msg_type: str, value: Any) -> bytes:
    """``value`` (a dict of the fields) as a CDR payload of ``msg_type``, header included."""
    store = _typestore()
    return bytes(store.serialize_cdr(message_of_value(msg_type, value), msg_type))


def value_of_message(message: Any) -> Any:
    """A rosbags message (or a field of one) as plain JSON-ready values: its
    fields only (not the type's constants, ``NavSatStatus.STATUS_FIX``, which
    rosbags's classes carry as attributes too, nor the member an empty
    message has on the wire)."""
    if hasattr(message, "__msgtype__"):
        _, fields = _typestore().fielddefs[message.__msgtype__]
        return {
            name: value_of_message(getattr(message, name))
            for name, _ in fields
            if name != EMPTY_MEMBER
        }
    if hasattr(message, "tolist"):  # a numpy array or scalar
        return message.tolist()
    if isinstance(message, list | tuple):
        return [value_of_message(v) for v in message]
    return message


def value_of_cdr(msg_type: str, payload: bytes) -> Any:
    """A CDR payload of ``msg_type`` (with its header, any padding after the
    message ignored: :func:`~cfgplan.ros2.rmw_zenoh.decode_cdr`) as a dict of its fields."""
    return value_of_message(decode_cdr(payload, msg_type))
