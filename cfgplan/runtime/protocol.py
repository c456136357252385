"""The switch protocol's messages (5.5, 7.3): every message between the coordinator and
the robots, typed, in one module that both sides build and read them with.

The coordinator (:mod:`cfgplan.reconfigure.network`) sends a robot, on the
robot's key ``cfgplan/<society>/<robot>/configure``, one of :data:`ToRobot`
(``{"op": ...}``); a robot (:mod:`cfgplan.runtime.member`) sends the
coordinator, on ``cfgplan/<society>/coordinator/<robot>``, one of
:data:`ToCoordinator` (``{"type": ...}``). Each message is a frozen dataclass;
:func:`encode` writes it as one line of JSON, :func:`read_to_robot` and
:func:`read_to_coordinator` read one back. Field ``sender`` is written
``from`` on the wire; a field left at its default (no ``part``, no
``reason``) is not written.

Messages come from other processes and are not trusted: reading one checks
its size (:data:`MAX_BYTES`), that it is a JSON object of a known ``op`` or
``type``, and each field's type and bounds (ids whole numbers from 0 to
:data:`MAX_ID`, names non-empty strings of at most :data:`MAX_NAME`
characters, texts at most :data:`MAX_TEXT`); anything else raises
:class:`ProtocolError`, which the receiver records and drops. A part is
carried as the JSON :func:`~cfgplan.runtime.part.part_to_json` writes and is
read by :func:`~cfgplan.runtime.part.part_from_json` where it is to run: a
part that cannot be read is *refused* with the reason (the coordinator learns
why), not dropped. Texts written by this side (a refusal's reason, a goal)
are clipped to :data:`MAX_TEXT`.

No pydantic here: emitted robot programs import this module, and pydantic
would double the time to import the runtime (measured: 133 ms against 119 ms
for all of ``cfgplan.runtime``, tests/runtime/test_imports.py).
"""

from __future__ import annotations

import json
import re
import secrets
from dataclasses import dataclass, field, fields
from enum import StrEnum
from typing import Any, ClassVar

from cfgplan.runtime.monitor import Detection
from cfgplan.runtime.wire import is_number, is_whole, loads

__all__ = [
    "MAX_BYTES",
    "MAX_FACTS",
    "MAX_GENERATION",
    "MAX_ID",
    "MAX_NAME",
    "MAX_TERMS",
    "MAX_TEXT",
    "MESSAGES",
    "Abort",
    "Ack",
    "CallError",
    "Commit",
    "Duplicate",
    "Finish",
    "Hello",
    "Phase",
    "Prepare",
    "ProtocolError",
    "Ready",
    "Report",
    "Rival",
    "State",
    "ToCoordinator",
    "ToRobot",
    "clip",
    "encode",
    "generation",
    "new_epoch",
    "read_to_coordinator",
    "read_to_robot",
]

MAX_BYTES = 1 << 20
"""A message longer than this (bytes of JSON) is not read (a part of a large
configuration is a few kilobytes)."""
MAX_ID = (1 << 53) - 1
"""The largest configuration id (every JSON reader holds it exactly)."""
MAX_NAME = 256
"""The longest robot name or epoch, in characters."""
MAX_TEXT = 4000
"""The longest text (a reason, a goal), in characters; longer ones are clipped when written."""
MAX_FACTS = 4096
"""The most facts (or instances, media, reliabilities) one list of a
:class:`State` carries; a coordinator whose situation holds more sends none."""
MAX_TERMS = 64
"""The most terms of one fact or instance (its predicate or name first)."""

Fact = tuple[str, ...]
"""A fact or a functionality instance as the wire carries it: ``("compass", "Emil")``."""


class ProtocolError(ValueError):
    """A message that is not one of this protocol: recorded and dropped by the receiver."""

    kind: str = "not a message"
    """What it claimed to be (its ``op`` or ``type``, when one of the
    protocol's), so that a receiver can say one of each kind at a time."""


class Phase(StrEnum):
    """What an :class:`Ack` answers."""

    READY = "ready"  # to a prepare: the part can run here
    REFUSED = "refused"  # to a prepare or a commit: it cannot (``reason``)
    INSTALLED = "installed"  # to a commit: the part runs from the next cycle on
    FINISHED = "finished"  # to a finish: this robot ends its run


MAX_GENERATION = 10**15 - 1
"""The highest generation an epoch counts (15 digits): a run claimed beyond
it is not followed."""
_GENERATION = re.compile(r"([0-9]{1,15})\.")


def new_epoch(generation: int = 1) -> str:
    """A coordinator's run, drawn when it starts coordinating:
    ``<generation>.<16 hex digits>``. A robot that takes over coordination
    counts one generation more than the run it followed; a robot fences
    off every run of a lower generation than the one it follows."""
    return f"{generation}.{secrets.token_hex(8)}"


def generation(epoch: str) -> int:
    """The generation an epoch counts (:func:`new_epoch`); 0 for one that
    counts none (written before generations were, or by a stranger)."""
    found = _GENERATION.match(epoch)
    return int(found.group(1)) if found else 0


def clip(text: str, most: int = MAX_TEXT) -> str:
    """``text`` cut to ``most`` characters (an ellipsis says it was)."""
    return text if len(text) <= most else text[: most - 1] + "…"


# -- coordinator to robot ------------------------------------------------------


@dataclass(frozen=True)
class Prepare:
    """Phase one of a switch: can the robot run ``part`` as configuration ``id``?
    Answered by an :class:`Ack` ``ready`` or ``refused``."""

    OP: ClassVar[str] = "prepare"
    id: int
    sender: str = field(metadata={"wire": "from"})
    epoch: str
    part: object = field(metadata={"part": True})


@dataclass(frozen=True)
class Commit:
    """Phase two: install the part prepared for ``id`` (or ``part`` itself,
    which re-synchronises a robot that appeared). Answered ``installed`` or
    ``refused``. ``step``: the step of the sequence of goals (7.3, from 0)
    the configuration serves, which a robot that takes over coordination
    goes on from."""

    OP: ClassVar[str] = "commit"
    id: int
    sender: str = field(metadata={"wire": "from"})
    epoch: str
    part: object = field(default=None, metadata={"part": True})
    step: int = 0


@dataclass(frozen=True)
class Abort:
    """Forget what was prepared for ``id``: the switch is made nowhere."""

    OP: ClassVar[str] = "abort"
    id: int
    sender: str = field(metadata={"wire": "from"})
    epoch: str


@dataclass(frozen=True)
class Finish:
    """The task (``goal``) is accomplished: end the run. Answered ``finished``."""

    OP: ClassVar[str] = "finish"
    id: int
    sender: str = field(metadata={"wire": "from"})
    epoch: str
    goal: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "goal", clip(self.goal))


@dataclass(frozen=True)
class Duplicate:
    """Another process runs this robot: the coordinator keeps the one whose
    :class:`Ready` came first, and the process of ``instance`` stops (a second
    process named Pippi would hide the first one's death: one liveliness
    token for both). Not answered."""

    OP: ClassVar[str] = "duplicate"
    sender: str = field(metadata={"wire": "from"})
    epoch: str
    instance: str


@dataclass(frozen=True)
class Hello:
    """The coordinator sees the robot's token but has no :class:`Ready` from
    it (the coordinator started after it): the robot answers :class:`Ready`."""

    OP: ClassVar[str] = "hello"
    sender: str = field(metadata={"wire": "from"})
    epoch: str


@dataclass(frozen=True)
class State:
    """What the society knows on top of the state it was started with, as it
    stands with configuration ``id`` committed (5.5, 7.2): the facts added and
    removed (by the operator, by the postconditions of the steps accomplished),
    the functionality instances out of service, the media down (indexes into
    the state's media), the reliabilities lowered, and the ``step`` of the
    sequence. Sent to every robot that is ready after each commit and each
    change that needed no switch; each keeps the last one of the run it
    follows, and a robot that takes over coordination plans from it
    (:mod:`cfgplan.reconfigure.committed`). Not answered."""

    OP: ClassVar[str] = "state"
    id: int
    sender: str = field(metadata={"wire": "from"})
    epoch: str
    step: int = 0
    added: tuple[Fact, ...] = ()
    removed: tuple[Fact, ...] = ()
    failed: tuple[Fact, ...] = ()
    down: tuple[int, ...] = ()
    reliability: tuple[tuple[Fact, float], ...] = ()


ToRobot = Prepare | Commit | Abort | Finish | Duplicate | Hello | State
"""A message on a robot's ``configure`` key."""


# -- robot to coordinator ------------------------------------------------------


@dataclass(frozen=True)
class Ack:
    """A robot's answer to step ``phase`` of switch ``id`` of coordinator ``epoch``."""

    TYPE: ClassVar[str] = "ack"
    robot: str
    id: int
    phase: Phase
    epoch: str
    reason: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "reason", clip(self.reason))


@dataclass(frozen=True)
class Report:
    """A detection of the robot's monitor, stamped with the configuration it ran."""

    TYPE: ClassVar[str] = "report"
    robot: str
    detection: Detection


@dataclass(frozen=True)
class Ready:
    """The robot's subscriber for switch messages exists: it can be sent its
    part. Sent once when the robot starts and again in answer to each
    :class:`Hello` (the coordinator's, repeated until a robot answers); the
    coordinator sends a robot nothing of a switch before it has this (a
    liveliness token appears before the subscriber is known)."""

    TYPE: ClassVar[str] = "ready"
    robot: str
    instance: str = ""
    """Drawn when the robot's process starts: two processes that claim one
    robot name differ in it (:class:`Duplicate`)."""


@dataclass(frozen=True)
class CallError:
    """A functionality of the robot failed a call though its resource did not
    (its implementation raised, or ran over its budget): what it said, so that
    the coordinator's console shows the real error and not only the staleness
    it leads to. Sent at the first failed call of a run of them."""

    TYPE: ClassVar[str] = "call-error"
    robot: str
    functionality: str  # its label and instance: ``F7: transform-info(Pippi, Emil, Door1)``
    error: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "functionality", clip(self.functionality))
        object.__setattr__(self, "error", clip(self.error))


@dataclass(frozen=True)
class Rival:
    """The robot follows a live coordinator, ``leader``, and a message of
    another coordinator's run (``epoch``) reached it: that one is a second
    coordinator of the society and stops (no split brain), or, fenced off by
    the later generation of the run the robot follows (``over``), steps
    down and follows it. Sent once per such epoch; the coordinator of
    another epoch only notes it."""

    TYPE: ClassVar[str] = "rival"
    robot: str
    epoch: str
    leader: str
    over: str = ""
    """The run the robot follows (``leader``'s epoch)."""


ToCoordinator = Ack | Report | Ready | CallError | Rival
"""A message on the coordinator's key."""

MESSAGES: tuple[type[ToRobot] | type[ToCoordinator], ...] = (
    Prepare,
    Commit,
    Abort,
    Finish,
    Duplicate,
    Hello,
    State,
    Ack,
    Report,
    Ready,
    CallError,
    Rival,
)
"""Every message of the protocol (the docs' protocol page is checked against it)."""

_TO_ROBOT: dict[str, type[ToRobot]] = {
    m.OP: m for m in (Prepare, Commit, Abort, Finish, Duplicate, Hello, State)
}
_TO_COORDINATOR: dict[str, type[ToCoordinator]] = {
    m.TYPE: m for m in (Ack, Report, Ready, CallError, Rival)
}


def tag(message: type[ToRobot] | type[ToCoordinator]) -> tuple[str, str]:
    """The key and value that name a message on the wire: ``("op", "prepare")``."""
    return ("op", message.OP) if hasattr(message, "OP") else ("type", message.TYPE)


def wire_fields(message: type[ToRobot] | type[ToCoordinator]) -> list[str]:
    """The names of a message's fields on the wire, after its tag."""
    return [f.metadata.get("wire", f.name) for f in fields(message)]


def encode(message: ToRobot | ToCoordinator) -> bytes:
    """``message`` as one line of JSON."""
    key, value = tag(type(message))
    out: dict[str, object] = {key: value}
    for f in fields(message):
        data = getattr(message, f.name)
        if data is None or (f.default in ("", 0, ()) and data == f.default):
            continue  # left at its default: not written
        if isinstance(data, Detection):
            data = json.loads(data.message())
        out[f.metadata.get("wire", f.name)] = data
    return json.dumps(out, separators=(",", ":")).encode()


def _object(payload: bytes) -> dict[str, object]:
    if len(payload) > MAX_BYTES:
        raise ProtocolError(f"a message of {len(payload)} bytes (at most {MAX_BYTES} are read)")
    try:
        data = loads(payload)
    except (ValueError, RecursionError) as exc:  # UnicodeDecodeError is a ValueError
        raise ProtocolError(f"not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ProtocolError("not a JSON object")
    return data


def _text(data: dict[str, object], key: str, most: int, *, empty: bool = True) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        raise ProtocolError(f"{key} is {value!r}, not a string")
    if len(value) > most:
        raise ProtocolError(f"{key} has {len(value)} characters (at most {most})")
    if not value and not empty:
        raise ProtocolError(f"{key} is missing or empty")
    return value


def _id(data: dict[str, object], key: str = "id", what: str = "a configuration id") -> int:
    value = data.get(key)
    if not is_whole(value) or not 0 <= value <= MAX_ID:
        raise ProtocolError(f"{key} is {value!r}, not {what} (0 to {MAX_ID})")
    return value


def _list(data: dict[str, object], key: str) -> list[object]:
    """The list under ``key`` (empty if absent), at most :data:`MAX_FACTS` long."""
    value = data.get(key, [])
    if not isinstance(value, list):
        raise ProtocolError(f"{key} is {value!r:.80}, not a list")
    if len(value) > MAX_FACTS:
        raise ProtocolError(f"{key} has {len(value)} entries (at most {MAX_FACTS})")
    return value


def _fact(value: object, key: str) -> Fact:
    """A fact or an instance: a list of 1 to :data:`MAX_TERMS` names."""
    if not isinstance(value, list) or not 1 <= len(value) <= MAX_TERMS:
        raise ProtocolError(f"{key}: {value!r:.80} is not a fact (1 to {MAX_TERMS} names)")
    for term in value:
        if not isinstance(term, str) or not 0 < len(term) <= MAX_NAME:
            raise ProtocolError(f"{key}: {term!r:.80} is not a name (1 to {MAX_NAME} characters)")
    return tuple(value)


def _reliability(value: object) -> tuple[Fact, float]:
    """An instance and its reliability, a number above 0 and at most 1 (7.2)."""
    if not isinstance(value, list) or len(value) != 2:
        raise ProtocolError(f"reliability: {value!r:.80} is not [instance, number]")
    instance, p = value
    if not is_number(p) or not 0.0 < p <= 1.0:
        raise ProtocolError(f"reliability: {p!r:.80} is not a number above 0, at most 1")
    return _fact(instance, "reliability"), float(p)


def _fields(message: type[ToRobot] | type[ToCoordinator], data: dict[str, object]) -> object:
    values: dict[str, Any] = {}
    for f in fields(message):
        key = f.metadata.get("wire", f.name)
        if f.name == "id":
            values[f.name] = _id(data)
        elif f.name == "step":
            values[f.name] = _id({key: data.get(key, 0)}, key, "a step of the sequence")
        elif f.name in ("sender", "robot", "leader"):
            values[f.name] = _text(data, key, MAX_NAME, empty=False)
        elif f.name in ("epoch", "over"):
            values[f.name] = _text(data, key, MAX_NAME)
        elif f.name == "instance":
            values[f.name] = _text(data, key, MAX_NAME, empty=message is not Duplicate)
        elif f.name in ("reason", "goal", "error"):
            values[f.name] = _text(data, key, MAX_TEXT)
        elif f.name == "functionality":
            values[f.name] = _text(data, key, MAX_TEXT, empty=False)
        elif f.name == "phase":
            phase = data.get(key)
            if not isinstance(phase, str) or phase not in Phase.__members__.values():
                raise ProtocolError(f"phase is {phase!r}, not one of {', '.join(Phase)}")
            values[f.name] = Phase(phase)
        elif f.name == "part":
            if key not in data and message is Prepare:
                raise ProtocolError("a prepare carries no part")
            values[f.name] = data.get(key)
        elif f.name in ("added", "removed", "failed"):
            values[f.name] = tuple(_fact(v, key) for v in _list(data, key))
        elif f.name == "down":
            values[f.name] = tuple(_id({key: v}, key, "a medium's index") for v in _list(data, key))
        elif f.name == "reliability":
            values[f.name] = tuple(_reliability(v) for v in _list(data, key))
        elif f.name == "detection":
            try:
                values[f.name] = Detection.read(json.dumps(data.get(key)).encode())
            except (ValueError, TypeError) as exc:
                raise ProtocolError(f"detection: {exc}") from None
        else:  # pragma: no cover  (a field added without a rule to read it)
            raise AssertionError(f"no rule reads field {f.name} of {message.__name__}")
    return message(**values)


def _read(payload: bytes, key: str, kinds: dict[str, type[Any]]) -> object:
    """The message ``payload`` holds, its class named by field ``key``."""
    data = _object(payload)
    tag = data.get(key)
    message = kinds.get(tag) if isinstance(tag, str) else None
    if message is None:
        raise ProtocolError(f"{key} is {tag!r}, not one of {', '.join(kinds)}")
    try:
        return _fields(message, data)
    except ProtocolError as exc:
        exc.kind = str(tag)
        raise


def read_to_robot(payload: bytes) -> ToRobot:
    """A message from the coordinator (:class:`ProtocolError` when it is none)."""
    out = _read(payload, "op", _TO_ROBOT)
    assert isinstance(out, ToRobot)
    return out


def read_to_coordinator(payload: bytes) -> ToCoordinator:
    """A message from a robot (:class:`ProtocolError` when it is none)."""
    out = _read(payload, "type", _TO_COORDINATOR)
    assert isinstance(out, ToCoordinator)
    return out
