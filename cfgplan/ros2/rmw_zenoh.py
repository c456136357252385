"""The wire format of rmw_zenoh (ROS 2's Zenoh middleware), as pure functions.

Everything here follows rmw_zenoh's design document (``docs/design.md`` of
ros2/rmw_zenoh) and its sources under ``rmw_zenoh_cpp/src/detail/``
(``liveliness_utils.cpp``, ``attachment_helpers.cpp``,
``rmw_publisher_data.cpp``, ``qos.cpp``), as released for ROS 2 Jazzy from
rmw_zenoh 0.2.4 (2025-04-20, the Jazzy series is 0.2.x) and for Rolling and
Kilted from 0.6.0: the releases whose ``attachment_helpers.cpp`` writes the
attachment as three values without keys ("Change serialization format",
the Jazzy backport of Rolling's change). Jazzy's 0.2.0 to 0.2.3 wrote
string keys before each value, which :func:`parse_attachment` refuses:

* a topic is the Zenoh key expression ``<domain_id>/<fully qualified name
  without its leading slash>/<type name>/<type hash>`` (design.md, "Topic and
  Service name mapping to Zenoh key expressions"): :func:`topic_key_expr`;
* every node and publisher declares a liveliness token under ``@ros2_lv``
  (design.md, "Graph Cache"), without which ``ros2 node list`` and ``ros2
  topic list`` do not show it: :func:`node_token`, :func:`publisher_token`;
* every message carries an attachment of 33 bytes, sequence number, source
  timestamp and publisher GID (design.md, "Publishers"): :func:`attachment`;
* payloads are CDR with the 4-byte encapsulation header (design.md,
  "Serialization/Deserialization"): :func:`string_cdr`.

No :mod:`zenoh` import: :mod:`cfgplan.ros2.bridge` puts these on a session.
``rosbags`` (CDR, RIHS01 type hashes) and ``xxhash`` (the GID) are imported
when first needed; missing, they raise a :class:`~cfgplan.runtime.errors.RunError`
naming ``pip install 'cfgplan[ros2]'``.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from functools import cache
from types import ModuleType
from typing import Any

from cfgplan.runtime.errors import RunError

__all__ = [
    "ADMIN_SPACE",
    "ATTACHMENT_BYTES",
    "DEFAULT_QOS",
    "GID_BYTES",
    "INSTALL",
    "PUBLISHER_QOS",
    "STRING",
    "Attachment",
    "QoS",
    "attachment",
    "check_name",
    "dds_type_name",
    "decode_cdr",
    "gid",
    "mangle",
    "node_name_of",
    "node_token",
    "parse_attachment",
    "publisher_token",
    "qos_key_expr",
    "string_cdr",
    "string_of_cdr",
    "subscriber_token",
    "topic_key_expr",
    "type_hash",
]

ADMIN_SPACE = "@ros2_lv"
"""The hermetic prefix of every liveliness token (design.md, "Graph Cache")."""

GID_BYTES = 16
"""``RMW_GID_STORAGE_SIZE`` (rmw/types.h, Iron and later)."""

ATTACHMENT_BYTES = 8 + 8 + 1 + GID_BYTES
"""Its size: two int64, the GID's one-byte length, the GID (design.md, "Publishers")."""

INSTALL = "pip install 'cfgplan[ros2]'"
CDR_LE = b"\x00\x01\x00\x00"
"""The encapsulation header of little-endian plain CDR (CDR_LE, options 0)."""

_TOKEN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _module(name: str) -> ModuleType:
    """``name`` imported, or a clear error naming the ``ros2`` extra."""
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError:
        raise RunError(
            f"ROS 2 interoperation needs the {name.split('.')[0]} package", hint=INSTALL
        ) from None


def check_name(name: str, what: str) -> str:
    """``name`` if it is a valid absolute ROS 2 name (``/a/b_c``), else ``ValueError``.

    The rules of design.ros2.org "Topic and Service name": tokens of letters,
    digits and underscores, not starting with a digit, separated by single
    slashes."""
    parts = name.split("/")
    if len(parts) < 2 or parts[0] != "" or not all(_TOKEN.match(p) for p in parts[1:]):
        raise ValueError(
            f"{name!r} is not an absolute ROS 2 {what} (e.g. /cfgplan/events: tokens of "
            "letters, digits and _, not starting with a digit)"
        )
    return name


def node_name_of(text: str) -> str:
    """A valid ROS 2 node name made from ``text`` (other characters become ``_``)."""
    name = re.sub(r"[^A-Za-z0-9_]", "_", text)
    return name if _TOKEN.match(name) else f"_{name}"


def mangle(name: str) -> str:
    """``name`` with every ``/`` written ``%`` (design.md, "Graph Cache": a
    mangled name; ``mangle_name`` in liveliness_utils.cpp)."""
    return name.replace("/", "%")


def dds_type_name(msg_type: str) -> str:
    """``std_msgs/msg/String`` as rmw_zenoh names it on the wire,
    ``std_msgs::msg::dds_::String_`` (design.md, "Topic and Service name mapping")."""
    parts = msg_type.split("/")
    if len(parts) != 3 or not all(parts):
        raise ValueError(f"{msg_type!r} is not a ROS 2 type name such as std_msgs/msg/String")
    package, kind, name = parts
    return f"{package}::{kind}::dds_::{name}_"


@cache
def _typestore() -> Any:
    typesys = _module("rosbags.typesys")
    return typesys.get_typestore(typesys.Stores.ROS2_JAZZY)


FIELD_TYPE_IDS = {
    "nested": 1,
    "int8": 2,
    "uint8": 3,
    "int16": 4,
    "uint16": 5,
    "int32": 6,
    "uint32": 7,
    "int64": 8,
    "uint64": 9,
    "float32": 10,
    "float64": 11,
    "bool": 15,
    "byte": 16,
    "string": 17,
    "wstring": 18,
    "bounded_string": 21,
    "bounded_wstring": 22,
}
"""The ``type_id`` of each field type in a type description
(type_description_interfaces/msg/FieldType.msg); an array adds 48, a bounded
sequence 96, an unbounded one 144."""

MSG_AS_IDL = {"char": "uint8"}
"""A ``.msg`` base type that rosidl turns into another IDL type before it
describes it: a ``.msg`` ``char`` is an IDL ``uint8`` (rosidl_adapter's
``MSG_TYPE_TO_IDL``), so its ``type_id`` is 3, not FieldType's ``CHAR``
(13), which only an IDL ``char`` has. (``byte`` is an IDL ``octet``: 16.)"""

NAME, ARRAY, SEQUENCE = 2, 3, 4
"""rosbags's ``Nodetype`` values (BASE is 1): a nested message, ``T[n]``, ``T[]``/``T[<=n]``."""


EMPTY_MEMBER = "structure_needs_at_least_one_member"
"""The one ``uint8`` member rosidl gives a message without fields (std_msgs/msg/Empty)."""


def _type_description(msg_type: str, fielddefs: Any) -> dict[str, Any]:
    """The REP-2016 type description of ``msg_type`` (its ``type_description``
    and ``referenced_type_descriptions``, sorted by name), the fields as
    rosidl_generator_type_description writes them, from rosbags's field
    definitions ``fielddefs``."""
    referenced: dict[str, dict[str, Any]] = {}

    def field(name: str, desc: Any) -> dict[str, Any]:
        kind, rest = desc
        increment = capacity = string_capacity = 0
        if kind == ARRAY:
            increment, (element, capacity) = 48, rest
            kind, rest = element
        elif kind == SEQUENCE:
            element, bound = rest
            increment, capacity = (96, bound) if bound else (144, 0)
            kind, rest = element
        nested = ""
        if kind == NAME:
            type_id, nested = FIELD_TYPE_IDS["nested"], rest
            describe(nested)
        else:
            base, bound = rest
            base = MSG_AS_IDL.get(base, base)
            if base in ("string", "wstring") and bound:
                base, string_capacity = f"bounded_{base}", bound
            type_id = FIELD_TYPE_IDS[base]
        return {
            "name": name,
            "type": {
                "type_id": increment + type_id,
                "capacity": capacity,
                "string_capacity": string_capacity,
                "nested_type_name": nested,
            },
        }

    def describe(name: str) -> dict[str, Any]:
        if name not in referenced:
            # an empty message has one uint8 member (rosidl's IDL of an empty .msg)
            fields = fielddefs[name][1] or [(EMPTY_MEMBER, (1, ("uint8", 0)))]
            referenced[name] = {"type_name": name, "fields": [field(n, d) for n, d in fields]}
        return referenced[name]

    top = describe(msg_type)
    return {
        "type_description": top,
        "referenced_type_descriptions": [
            described for name, described in sorted(referenced.items()) if name != msg_type
        ],
    }


def type_hash(msg_type: str) -> str:
    """The REP-2016 hash of ``msg_type``, ``RIHS01_<64 hex digits>``, as
    rosidl generates it (design.md: ``<type_hash>``): SHA-256 of the JSON of
    its type description (:func:`_type_description`, from rosbags's ROS 2
    Jazzy type definitions), written as rosidl's ``json.dumps`` does."""
    import hashlib
    import json

    described = _type_description(msg_type, _typestore().fielddefs)
    return "RIHS01_" + hashlib.sha256(json.dumps(described).encode()).hexdigest()


def topic_key_expr(domain_id: int, topic: str, type_name: str, hash_: str) -> str:
    """The Zenoh key expression of a topic, ``<domain_id>/<fully qualified
    name>/<type name>/<type hash>``, the name without its leading (or
    trailing) slash (design.md, "Topic and Service name mapping"; ``TopicInfo``
    in liveliness_utils.cpp). E.g. ``0/chatter/std_msgs::msg::dds_::String_/RIHS01_df66...``."""
    return f"{domain_id}/{topic.strip('/')}/{type_name}/{hash_}"


@dataclass(frozen=True)
class QoS:
    """The QoS policies a token carries, with rmw_zenoh's enumerations (rmw/types.h).

    The defaults are rmw_zenoh's own (``qos.cpp``: reliable, volatile, keep
    last 42); deadline, lifespan and liveliness are always rmw_zenoh's
    defaults here (infinite, automatic), the only ones it implements."""

    reliability: int = 1  # RMW_QOS_POLICY_RELIABILITY_RELIABLE (2: best effort)
    durability: int = 2  # RMW_QOS_POLICY_DURABILITY_VOLATILE (1: transient local)
    history: int = 1  # RMW_QOS_POLICY_HISTORY_KEEP_LAST (2: keep all)
    depth: int = 42


DEFAULT_QOS = QoS()
"""rmw_zenoh's default QoS: its fields are left empty in a token."""

PUBLISHER_QOS = QoS(depth=10)
"""rclcpp's default publisher QoS (reliable, volatile, keep last 10)."""


def qos_key_expr(qos: QoS) -> str:
    """The QoS part of a token: ``<reliability>:<durability>:<history>,<depth>:
    <deadline s>,<ns>:<lifespan s>,<ns>:<liveliness>,<lease s>,<ns>``, each field
    empty when it is rmw_zenoh's default (``qos_to_keyexpr`` in
    liveliness_utils.cpp; design.md's talker example ends ``::,7:,:,:,,``)."""

    def part(value: int, default: int) -> str:
        return "" if value == default else str(value)

    d = DEFAULT_QOS
    return (
        f"{part(qos.reliability, d.reliability)}:{part(qos.durability, d.durability)}:"
        f"{part(qos.history, d.history)},{part(qos.depth, d.depth)}:,:,:,,"
    )


def _entity(
    domain_id: int,
    session_id: str,
    node_id: int,
    entity_id: int,
    kind: str,
    node: str,
    namespace: str,
    enclave: str,
) -> str:
    return "/".join(
        (
            ADMIN_SPACE,
            str(domain_id),
            session_id,
            str(node_id),
            str(entity_id),
            kind,
            mangle(enclave),
            mangle(namespace),
            node,
        )
    )


def node_token(
    domain_id: int,
    session_id: str,
    node_id: int,
    node: str,
    *,
    namespace: str = "/",
    enclave: str = "/",
) -> str:
    """The liveliness token of a node: ``@ros2_lv/<domain_id>/<session_id>/
    <node_id>/<node_id>/NN/<mangled enclave>/<mangled namespace>/<node name>``
    (design.md, "Graph Cache"; the root namespace and the default enclave are
    ``/``, mangled ``%``). ``session_id`` is the Zenoh session id in hex
    (``str(session.zid())``)."""
    return _entity(domain_id, session_id, node_id, node_id, "NN", node, namespace, enclave)


def publisher_token(
    domain_id: int,
    session_id: str,
    node_id: int,
    entity_id: int,
    node: str,
    topic: str,
    type_name: str,
    hash_: str,
    qos: QoS = PUBLISHER_QOS,
    *,
    namespace: str = "/",
    enclave: str = "/",
) -> str:
    """The liveliness token of a message publisher (``MP``): the node's fields,
    then ``<mangled topic>/<type name>/<type hash>/<qos>`` (design.md, "Graph
    Cache"; e.g. ``.../MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/
    RIHS01_df66.../::,7:,:,:,,``)."""
    head = _entity(domain_id, session_id, node_id, entity_id, "MP", node, namespace, enclave)
    return _topic_token(head, topic, type_name, hash_, qos)


def subscriber_token(
    domain_id: int,
    session_id: str,
    node_id: int,
    entity_id: int,
    node: str,
    topic: str,
    type_name: str,
    hash_: str,
    qos: QoS = PUBLISHER_QOS,
    *,
    namespace: str = "/",
    enclave: str = "/",
) -> str:
    """The liveliness token of a message subscription (``MS``): as
    :func:`publisher_token`, kind ``MS`` (design.md, "Graph Cache")."""
    head = _entity(domain_id, session_id, node_id, entity_id, "MS", node, namespace, enclave)
    return _topic_token(head, topic, type_name, hash_, qos)


def _topic_token(head: str, topic: str, type_name: str, hash_: str, qos: QoS) -> str:
    """An entity's token, then its topic, type, type hash and QoS (design.md)."""
    return f"{head}/{mangle(topic)}/{mangle(type_name)}/{mangle(hash_)}/{qos_key_expr(qos)}"


def gid(token: str) -> bytes:
    """The 16-byte GID of the entity whose liveliness token is ``token``:
    XXH3-128 of the token, its low 64 bits then its high 64 bits, little
    endian (``Entity::Entity`` in liveliness_utils.cpp, on a little-endian host)."""
    xxhash = _module("xxhash")
    digest = int(xxhash.xxh3_128_intdigest(token.encode()))
    return digest.to_bytes(GID_BYTES, "little")


@dataclass(frozen=True)
class Attachment:
    """What every rmw_zenoh message carries beside its payload."""

    sequence_number: int
    source_timestamp: int  # ns since the UNIX epoch
    gid: bytes


def attachment(sequence_number: int, source_timestamp: int, gid_: bytes) -> bytes:
    """The 33-byte attachment of a message (design.md, "Publishers";
    ``AttachmentData::serialize_to_zbytes`` in attachment_helpers.cpp, zenoh-ext
    serialization): the sequence number (int64 LE, from 1 per publisher), the
    source timestamp (int64 LE, ns since the epoch), the GID's length as one
    byte (LEB128 of 16) and the 16-byte GID."""
    if len(gid_) != GID_BYTES:
        raise ValueError(f"a GID has {GID_BYTES} bytes, not {len(gid_)}")
    return struct.pack("<qqB", sequence_number, source_timestamp, GID_BYTES) + gid_


def parse_attachment(data: bytes) -> Attachment:
    """The fields of a 33-byte attachment (:func:`attachment`); ``ValueError``
    for another layout (rmw_zenoh before Jazzy's 0.2.4 and Rolling's 0.6.0
    put string keys before the values)."""
    if len(data) != ATTACHMENT_BYTES or data[16] != GID_BYTES:
        raise ValueError(f"not an rmw_zenoh attachment of {ATTACHMENT_BYTES} bytes: {data.hex()}")
    sequence_number, source_timestamp = struct.unpack_from("<qq", data)
    return Attachment(sequence_number, source_timestamp, bytes(data[17:]))


STRING = "std_msgs/msg/String"


def string_cdr(text: str) -> bytes:
    """A ``std_msgs/msg/String`` holding ``text`` in CDR with its 4-byte
    encapsulation header ``00 01 00 00`` (little endian), serialized by rosbags
    (design.md, "Serialization/Deserialization")."""
    store = _typestore()
    message = store.types[STRING](data=text)
    return bytes(store.serialize_cdr(message, STRING))


def decode_cdr(payload: bytes, msg_type: str) -> Any:
    """The rosbags message of type ``msg_type`` in a CDR payload (with its
    4-byte encapsulation header, big or little endian); ``ValueError`` for
    another header or a payload too short or malformed for the type.

    Bytes after the message are padding and are ignored, as every ROS 2
    middleware's deserializer (Fast CDR) ignores them: rclpy's
    ``serialize_message`` pads its buffer (a ``sensor_msgs/msg/JointState`` to
    8 bytes more than its fields), which rosbags's own ``deserialize_cdr``
    refuses as a "size mismatch" past 3 bytes."""
    if payload[:2] not in (b"\x00\x00", b"\x00\x01"):
        raise ValueError(f"not a plain CDR payload: header {payload[:4].hex()}")
    store = _typestore()
    definition = store.get_msgdef(msg_type)
    read = definition.deserialize_cdr_le if payload[1] else definition.deserialize_cdr_be
    errors = _module("rosbags.serde").SerdeError
    try:
        message, _ = read(memoryview(payload)[4:], 0, definition.cls, store)
    except (errors, struct.error, UnicodeDecodeError, ValueError, IndexError) as exc:
        raise ValueError(f"not a CDR {msg_type}: {exc}") from None
    return message


def string_of_cdr(payload: bytes) -> str:
    """The text of a CDR ``std_msgs/msg/String`` (:func:`string_cdr`), read by rosbags."""
    return str(decode_cdr(payload, STRING).data)
