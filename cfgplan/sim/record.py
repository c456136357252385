"""What a simulation records: the trace, the events that matter, the
configurations that ran and when.

The :class:`Recorder` listens to every robot (a runtime listener, 5.5). Each
event becomes one JSON line of the trace, the runtime's schema
(:mod:`cfgplan.runtime.schema`) with simulated time: ``"t"`` is the
simulation's clock, and the fields that measure the host's wall clock — a call's ``duration``, a
switch's ``plan_ms`` and ``latency``, a message's ``sent`` — are left out,
so that one seed gives one trace, byte for byte. Values longer than
:data:`ELIDE` characters of JSON (a laser scan) are written by their type,
size and digest, ``{"$elided": "dict", "$bytes": 5210, "$sha256": "..."}``:
the rule of the runtime's ``--trace``
(:func:`~cfgplan.runtime.tracefile.elided`) with a shorter limit.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import IO, Any

from cfgplan.configuration.model import Configuration
from cfgplan.planner.task import Ground
from cfgplan.runtime.events import STORY_KINDS, Adaptation, Call, Event
from cfgplan.runtime.tracefile import elided
from cfgplan.sim.world import World

__all__ = ["ELIDE", "Notable", "Recorder", "Segment"]

ELIDE = 400
"""Characters of JSON beyond which a value is elided in the trace."""

_WALL_CLOCK = ("duration", "plan_ms", "latency", "sent")


@dataclass(frozen=True)
class Notable:
    """An event of monitoring and reconfiguration, at simulated time ``t``."""

    t: float
    what: str
    record: dict[str, Any]


@dataclass
class Segment:
    """A configuration that ran from ``start`` to ``end`` for ``goal`` (``None``: nothing ran)."""

    id: int
    config: Configuration | None
    goal: Ground
    start: float
    end: float | None = None


@dataclass
class Recorder:
    """A listener of every robot of a simulated society (module docstring)."""

    world: World
    trace: IO[str] | None = None
    echo: Callable[[str], None] | None = None
    notable: list[Notable] = field(default_factory=list)
    last_calls: dict[tuple[str, ...], Call] = field(default_factory=dict)
    segments: list[Segment] = field(default_factory=list)
    lines: int = 0

    def __call__(self, event: Event) -> None:
        if isinstance(event, Call):
            self.last_calls[event.instance] = event
        record = elided(event, ELIDE).record()
        now = round(self.world.time, 4)
        record["t"] = now
        for key in _WALL_CLOCK:
            record.pop(key, None)
        if self.trace is not None:
            self.trace.write(json.dumps(record, separators=(",", ":"), sort_keys=False) + "\n")
            self.lines += 1
        if isinstance(event, Adaptation) and event.what in STORY_KINDS:
            self.notable.append(Notable(now, event.what, record))
            if self.echo is not None:
                self.echo(_line(record))

    def running(self, reconfigurator_id: int, config: Configuration | None, goal: Ground) -> None:
        """After each pass: note a new configuration when the society switched."""
        if self.segments and self.segments[-1].id == reconfigurator_id:
            return
        now = round(self.world.time, 4)
        if self.segments:
            self.segments[-1].end = now
        self.segments.append(Segment(reconfigurator_id, config, goal, now))

    def close(self) -> None:
        if self.segments and self.segments[-1].end is None:
            self.segments[-1].end = round(self.world.time, 4)

    def of(self, *what: str) -> list[Notable]:
        return [n for n in self.notable if n.what in what]


def _line(record: dict[str, Any]) -> str:
    t = f"{record['t']:7.1f} s"
    what = record["event"]
    if what == "switch":
        was = "nothing" if record["from_cost"] is None else record["from_cost"]
        return (
            f"{t}  switch {was} -> {record['to_cost']} "
            f"({record['cause']}; {record['source'] or 'installed'})"
        )
    if what == "failure":
        said = f": {detail(str(record['detail']))}" if record.get("detail") else ""
        seen = f"{record['how']}, seen by {record['detected_by']}"
        return f"{t}  failure of {record['resource']} ({seen}){said}"
    if what == "recovery":
        return f"{t}  {record['resource']} works again ({record['how']})"
    if what == "achieved":
        return f"{t}  accomplished: {record['functionality']}"
    if what == "no-configuration":
        return f"{t}  no admissible configuration ({record['cause']})"
    if what == "inject":
        return f"{t}  scripted: {record['spec']}"
    if what == "abort":
        return f"{t}  switch aborted: {record['reason']}"
    return f"{t}  {what}: " + ", ".join(
        f"{k}={record[k]}" for k in ("added", "removed") if k in record
    )


_RAISED = re.compile(
    r"^the implementation raised ResourceFailure: (?P<what>.*?)(?: \([^()]*:\d+ in [^()]*\))?$"
)


def detail(text: str) -> str:
    """What a resource failure said, without the implementation's file and line."""
    found = _RAISED.match(text)
    return found.group("what") if found else text
