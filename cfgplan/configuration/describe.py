"""Configuration descriptions: the thesis's text form (4.4, 4.6) and JSON.

The text form is the thesis's own::

    (configuration
      Functionalities:
        F3: cross-door(Pippi, Door1)
      Channels:
        local(Emil, F8, F14, image(Emil))
        global(Emil, Pippi, F7, F3, pos(Pippi, Door1), 20)
      Cost: 44
    )

A local channel names its robot, a global one sender then receiver; the
bandwidth follows the data when one is declared. ``Postconditions:``,
``Media:`` and ``Devices:`` (agents the state declares devices) are added
when there is something to show.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from cfgplan.configuration.cost import fmt
from cfgplan.configuration.model import Channel, Configuration
from cfgplan.ir.model import Medium
from cfgplan.notation import call_text


def channel_text(ch: Channel) -> str:
    robots = ch.source_robot if ch.kind == "local" else f"{ch.source_robot}, {ch.target_robot}"
    bandwidth = "" if ch.bandwidth is None else f", {fmt(ch.bandwidth)}"
    return f"{ch.kind}({robots}, {ch.source}, {ch.target}, {call_text(ch.data)}{bandwidth})"


def media_loads(config: Configuration, media: Sequence[Medium]) -> list[tuple[Medium, float]]:
    """Each medium with the bandwidth the configuration puts on it."""
    loads = [0.0] * len(media)
    for a in config.media:
        loads[a.medium] += config.channels[a.channel].bandwidth or 0.0
    return list(zip(media, loads, strict=True))


def to_text(config: Configuration, media: Sequence[Medium] = (), title: str = "") -> str:
    """The configuration description of 4.4/4.6."""
    lines = [f"(configuration{' ' + title if title else ''}", "  Functionalities:"]
    lines += [f"    {f}" for f in config.functionalities]
    lines.append("  Channels:")
    lines += [f"    {channel_text(c)}" for c in config.channels]
    if config.postconditions:
        lines.append("  Postconditions:")
        lines += [f"    {p}" for p in config.postconditions]
    if media:
        lines.append("  Media:")
        for medium, load in media_loads(config, media):
            lines.append(
                f"    medium({medium.type}, {medium.sender}, {medium.receiver}, "
                f"{fmt(medium.capacity)}): load {fmt(load)}"
            )
    if config.devices:
        lines.append(f"  Devices: {', '.join(config.devices)}")
    lines.append(f"  Cost: {fmt(config.cost)}")
    lines.append(")")
    return "\n".join(lines)


def to_dict(config: Configuration, rank: int, media: Sequence[Medium] = ()) -> dict[str, Any]:
    """One configuration in the public JSON schema (:mod:`cfgplan.configuration.schema`);
    with the state's ``media``, the load the configuration puts on each."""
    robot = {f.label: f.robot for f in config.functionalities}
    assigned = {a.channel: a.medium for a in config.media}
    loads = (
        {"media_loads": [_number(load) for _, load in media_loads(config, media)]} if media else {}
    )
    return {
        "rank": rank,
        "cost": _number(config.cost),
        "robots": config.robots,
        "devices": list(config.devices),
        "reliability": config.reliability,
        "derivation": config.derivation,
        "proven": config.proven,
        "functionalities": [
            {"id": f.label, "name": f.name, "args": list(f.args), "robot": f.robot}
            for f in config.functionalities
        ],
        "channels": [
            {
                "kind": c.kind,
                "from": c.source,
                "to": c.target,
                "from_robot": robot[c.source],
                "to_robot": robot[c.target],
                "data": list(c.data),
                "bandwidth": None if c.bandwidth is None else _number(c.bandwidth),
                "medium": assigned.get(i),
            }
            for i, c in enumerate(config.channels)
        ],
        "postconditions": list(config.postconditions),
        **loads,
    }


def _number(x: float) -> int | float:
    return int(x) if float(x).is_integer() else x


def medium_dict(medium: Medium) -> dict[str, Any]:
    return {
        "type": medium.type,
        "from": medium.sender,
        "to": medium.receiver,
        "capacity": _number(medium.capacity),
        "reliability": None if medium.reliability is None else _number(medium.reliability),
    }


def to_json(
    goal: Sequence[str],
    configs: Sequence[Configuration],
    media: Sequence[Medium],
    stats: dict[str, Any],
    extra: dict[str, Any] | None = None,
    first: int = 1,
) -> str:
    """The whole answer of ``cfgplan plan --format json``; keys in a fixed
    order, ``extra`` (e.g. ``"fallbacks"``, ``"explanation"``) last; the
    configurations ranked from ``first``."""
    doc = {
        "goal": call_text(goal),
        "configurations": [to_dict(c, i, media) for i, c in enumerate(configs, first)],
        "communication_checked": bool(media),
        **({"media": [medium_dict(m) for m in media]} if media else {}),
        "stats": stats,
        **(extra or {}),
    }
    return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"
