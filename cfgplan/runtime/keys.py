"""Where a society's data lives on the network: the Zenoh key expressions (5.2.2).

One robot program per robot; robots of one *society* share a prefix, so two
societies on one network stay apart::

    cfgplan/<society>/<robot>/alive                                     the robot runs
    cfgplan/<society>/<robot>/process/<instance>                        one process of it
    cfgplan/<society>/<robot>/ch/<sender>/<source>/<target>/<data ...>  a channel into it
    cfgplan/<society>/<robot>/configure                                 switches, to it
    cfgplan/<society>/coordinator/<robot>                               its reports, acks (5.5)
    cfgplan/<society>/<robot>/problem/<fingerprint>/<about>            the problem it runs
    cfgplan/<society>/<robot>/problem/<fingerprint>                     it plans it (5.5)

``<robot>`` is the robot that *receives*, ``<sender>`` the robot that sends;
``<source>`` and ``<target>`` are the channel's functionality labels and
``<data ...>`` its data descriptor, one chunk per element, e.g. the channel
from Emil's F7 to Pippi's F3 carrying ``(pos Pippi Door1)`` in society
``lab`` is ``cfgplan/lab/Pippi/ch/Emil/F7/F3/pos/Pippi/Door1``. A receiver
listens only to the key naming the sender it expects, and with ``--keys``
Zenoh's access control lets a robot put only on keys that name it as the
sender (:mod:`cfgplan.security.zenoh_tls`): no robot can pass its values off
as another's. Each chunk is
percent-encoded: letters, digits and ``_ . - + = , : ~`` stay as they are,
any other character becomes ``%XX`` per UTF-8 byte (so ``/``, ``*``, ``$``,
``#``, ``?``, ``@`` and ``%`` never reach Zenoh raw). A chunk is never empty.
"""

from __future__ import annotations

from cfgplan.key_chunks import PREFIX, chunk, unchunk
from cfgplan.runtime.transport import ChannelKey

__all__ = [
    "MAX_PROBLEM_KEY",
    "PREFIX",
    "alive_key",
    "alive_pattern",
    "channel_key",
    "channels_pattern",
    "chunk",
    "configure_key",
    "coordinator_key",
    "planner_key",
    "planner_of_token",
    "planner_pattern",
    "problem_key",
    "problem_of_token",
    "problem_pattern",
    "process_key",
    "process_of_token",
    "process_pattern",
    "robot_of_alive",
    "unchunk",
]


def channel_key(society: str, robot: str, key: ChannelKey, sender: str) -> str:
    """Where ``sender`` publishes the data of channel ``key`` into ``robot``."""
    parts = [PREFIX, society, robot, "ch", sender, key.source, key.target, *key.data]
    return "/".join(p if i == 0 or i == 3 else chunk(p) for i, p in enumerate(parts))


def channels_pattern(society: str, robot: str) -> str:
    """Every global channel into ``robot`` (one subscriber for all of them)."""
    return f"{PREFIX}/{chunk(society)}/{chunk(robot)}/ch/**"


def configure_key(society: str, robot: str) -> str:
    """Where the coordinator sends ``robot`` the steps of a switch (5.5)."""
    return f"{PREFIX}/{chunk(society)}/{chunk(robot)}/configure"


def coordinator_key(society: str, robot: str) -> str:
    """Where ``robot`` sends the coordinator its detections and answers: a key
    of its own, so that the coordinator knows who speaks (and, with
    ``--keys``, Zenoh's access control lets only ``robot`` put there)."""
    return f"{PREFIX}/{chunk(society)}/coordinator/{chunk(robot)}"


def alive_key(society: str, robot: str) -> str:
    """The liveliness token a running robot program declares."""
    return f"{PREFIX}/{chunk(society)}/{chunk(robot)}/alive"


def alive_pattern(society: str) -> str:
    """Every robot of ``society`` (for a liveliness subscriber)."""
    return f"{PREFIX}/{chunk(society)}/*/alive"


def process_key(society: str, robot: str, instance: str) -> str:
    """The liveliness token of one process of ``robot`` (``instance``: drawn
    when it starts): two processes of a robot declare the same ``alive``
    token, which Zenoh shows as one, but each its own of these."""
    return f"{PREFIX}/{chunk(society)}/{chunk(robot)}/process/{chunk(instance)}"


def process_pattern(society: str) -> str:
    """Every process of every robot of ``society`` (for the coordinator)."""
    return f"{PREFIX}/{chunk(society)}/*/process/*"


def process_of_token(key: str, society: str) -> tuple[str, str] | None:
    """The robot and instance a process token of ``society`` names, or ``None``."""
    named = _token(key, society, "process", 5)
    return None if named is None else (named[0], named[1])


def _token(key: str, society: str, kind: str, size: int) -> list[str] | None:
    """``cfgplan/<society>/<robot>/<kind>/...`` in ``size`` chunks: the robot
    and the chunks after ``kind``, read back; ``None`` when ``key`` is not
    that or a chunk was not written by :func:`chunk`."""
    parts = key.split("/")
    if len(parts) != size or parts[0] != PREFIX or parts[1] != chunk(society):
        return None
    if parts[3] != kind:
        return None
    try:
        return [unchunk(p) for p in (parts[2], *parts[4:])]
    except (UnicodeDecodeError, ValueError):  # not written by chunk: no robot of ours
        return None


def robot_of_alive(key: str, society: str) -> str | None:
    """The robot a liveliness key of ``society`` names, or ``None``."""
    named = _token(key, society, "alive", 4)
    return None if named is None else named[0]


def problem_key(society: str, robot: str, fingerprint: str, about: str) -> str:
    """The liveliness token by which ``robot`` says which problem it runs
    (:mod:`cfgplan.security.identity`): its fingerprint and a description."""
    return f"{PREFIX}/{chunk(society)}/{chunk(robot)}/problem/{chunk(fingerprint)}/{chunk(about)}"


def problem_pattern(society: str) -> str:
    """The problem tokens of every robot of ``society``."""
    return f"{PREFIX}/{chunk(society)}/*/problem/*/*"


MAX_PROBLEM_KEY = 2048
"""The longest problem token read (a description of 160 characters, escaped, fits)."""


def problem_of_token(key: str, society: str) -> tuple[str, str, str] | None:
    """The robot, fingerprint and description a problem token of ``society``
    names, or ``None`` (not one, too long, not written by :func:`chunk`)."""
    if len(key) > MAX_PROBLEM_KEY:
        return None
    named = _token(key, society, "problem", 6)
    return None if named is None else (named[0], named[1], named[2])


def planner_key(society: str, robot: str, fingerprint: str) -> str:
    """The liveliness token by which ``robot`` says it runs the problem of
    ``fingerprint`` with the planner, so that it may take over coordination
    (:func:`cfgplan.runtime.succession.candidates`; a robot run from emitted
    code announces its problem but not this)."""
    return f"{PREFIX}/{chunk(society)}/{chunk(robot)}/problem/{chunk(fingerprint)}"


def planner_pattern(society: str) -> str:
    """The planner tokens of every robot of ``society``."""
    return f"{PREFIX}/{chunk(society)}/*/problem/*"


def planner_of_token(key: str, society: str) -> tuple[str, str] | None:
    """The robot and fingerprint a planner token of ``society`` names, or ``None``."""
    named = _token(key, society, "problem", 5)
    return None if named is None else (named[0], named[1])
