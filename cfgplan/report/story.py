"""What a run's pictures show, whoever ran it: a :class:`Story`.

A story is the robots, the steps (goals), the configurations that ran and
when (:class:`Span`, numbered like the ``configuration-N`` files), and the
moments that matter (:class:`Mark`: switches and no-configuration, 5.5 and
7.2; failures and recoveries, on the row of the robot whose resource it is;
world changes; the bar falling). The pictures (:mod:`cfgplan.sim.timeline`,
:mod:`cfgplan.sim.diagrams`) draw a story; a simulation makes it from its
:class:`~cfgplan.sim.run.Run` (:mod:`cfgplan.sim.story`), ``cfgplan report``
from the events of a trace (:func:`from_records`, the lines of
:mod:`cfgplan.runtime.schema`), with a simulation's ``summary.json`` when it
sits beside the trace (its steps, title and world changes).

The configurations of a trace come from its switch events (the parts kept,
stopped and started: the first configuration is what the first switch kept
and stopped); a run that never switched is read from its calls (the
functionalities, and the local channels between a call's outputs and
another's inputs) and its sends (the global channels).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from cfgplan.configuration.cost import fmt
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance

__all__ = [
    "Mark",
    "Span",
    "Step",
    "Story",
    "configuration_of",
    "cost_text",
    "from_records",
    "owner",
    "role",
]

Record = dict[str, Any]


@dataclass(frozen=True)
class Step:
    """A goal of the run: when it started and when it was accomplished (``None``: not)."""

    goal: str
    started: float | None
    achieved: float | None


@dataclass(frozen=True)
class Span:
    """Configuration ``number`` (``configuration-N``) ran from ``start`` to ``end`` for ``goal``."""

    number: int
    config: Configuration
    start: float
    end: float
    goal: str = ""


@dataclass(frozen=True)
class Mark:
    """A moment: ``what`` is ``switch``, ``no-configuration``, ``failure``,
    ``recovery``, ``change`` (the world) or ``drop`` (the bar); ``robot`` is
    the row it belongs to (empty: the whole society)."""

    t: float
    what: str
    text: str
    robot: str = ""
    record: Record = field(default_factory=dict, compare=False)


@dataclass
class Story:
    """Everything the timeline and the diagrams need (module docstring)."""

    title: str
    robots: list[str]
    end: float
    steps: list[Step] = field(default_factory=list)
    spans: list[Span] = field(default_factory=list)
    marks: list[Mark] = field(default_factory=list)
    clock: str = "simulated time (s)"

    def of(self, *what: str) -> list[Mark]:
        return [m for m in self.marks if m.what in what]

    def configurations(self) -> dict[int, Span]:
        """Each numbered configuration's first span."""
        out: dict[int, Span] = {}
        for span in self.spans:
            out.setdefault(span.number, span)
        return out


def role(config: Configuration, robot: str) -> str:
    """What ``robot`` does in ``config``: its action, else how many functionalities it runs."""
    mine = [f for f in config.functionalities if f.robot == robot]
    sinks = [f for f in mine if not any(c.source == f.label for c in config.channels)]
    if sinks:
        return ", ".join(f.name for f in sinks)
    return f"helps ({len(mine)} functionalities)"


def owner(resource: str, robots: Sequence[str], fallback: str = "") -> str:
    """The robot a resource belongs to: ``compass(Emil)`` is Emil's, ``Emil`` is Emil."""
    if resource in robots:
        return resource
    found = _CALL.match(resource)
    if found and found.group("args"):
        first = found.group("args").split(",")[0].strip()
        if first in robots:
            return first
    return fallback


_INSTANCE = re.compile(r"^(?P<label>[^:\s]+): (?P<name>[^()]+)\((?P<args>.*)\)$")
_CALL = re.compile(r"^(?P<name>[^()\s]+)\((?P<args>.*)\)$")
_CHANNEL = re.compile(r"^(?P<source>\S+)->(?P<target>\S+) (?P<data>.+)$")


def _args(text: str) -> tuple[str, ...]:
    return tuple(a.strip() for a in text.split(",") if a.strip())


def _data(text: str) -> tuple[str, ...]:
    """``pos(Emil, Door1)`` or ``(pos Emil Door1)`` as ``("pos", "Emil", "Door1")``."""
    text = text.strip()
    if text.startswith("(") and text.endswith(")"):
        return tuple(text[1:-1].split())
    found = _CALL.match(text)
    return (found.group("name"), *_args(found.group("args"))) if found else (text,)


def configuration_of(
    functionalities: Iterable[str], channels: Iterable[str | tuple[str, str, tuple[str, ...]]]
) -> Configuration | None:
    """A configuration from its printed parts (``F3: cross-door(Pippi, Door1)``,
    ``F7->F3 pos(Pippi, Door1)``); ``None`` when no functionality reads."""
    fs: dict[str, FunctionalityInstance] = {}
    for text in functionalities:
        found = _INSTANCE.match(text)
        if found:
            args = _args(found.group("args"))
            if args:
                label = found.group("label")
                fs[label] = FunctionalityInstance(label=label, name=found.group("name"), args=args)
    if not fs:
        return None
    chans: dict[tuple[str, str, tuple[str, ...]], Channel] = {}
    for ch in channels:
        if isinstance(ch, str):
            found = _CHANNEL.match(ch)
            if not found:
                continue
            source, target, data = found["source"], found["target"], _data(found["data"])
        else:
            source, target, data = ch
        if source not in fs or target not in fs:
            continue
        a, b = fs[source].robot, fs[target].robot
        kind = "local" if a == b else "global"
        chans[(source, target, data)] = Channel(
            kind=kind, source=source, target=target, source_robot=a, target_robot=b, data=data
        )
    return Configuration(functionalities=tuple(fs.values()), channels=tuple(chans.values()), cost=0)


def _identity(config: Configuration) -> object:
    return config.identity()[:2]


def _parts(record: Record, *names: str) -> tuple[list[str], list[str]]:
    fs: list[str] = []
    cs: list[str] = []
    for name in names:
        part = record.get(name)
        if isinstance(part, dict):
            fs += [str(x) for x in part.get("functionalities") or []]
            cs += [str(x) for x in part.get("channels") or []]
    return fs, cs


def _from_calls(records: Sequence[Record], until: float) -> Configuration | None:
    """What ran before ``until``, read from the calls and the sends (module docstring)."""
    fs: dict[str, str] = {}
    produced: dict[tuple[str, tuple[str, ...]], str] = {}
    wanted: list[tuple[str, str, tuple[str, ...]]] = []
    channels: list[str | tuple[str, str, tuple[str, ...]]] = []
    for r in records:
        if float(r.get("t", 0)) >= until:
            break
        if r.get("event") == "call" and r.get("label"):
            label = str(r["label"])
            fs[label] = f"{label}: {r.get('functionality')}({', '.join(r.get('args') or [])})"
            robot = str(r.get("robot"))
            for out in r.get("outputs") or []:
                produced[(robot, tuple(out.get("data") or ()))] = label
            for inp in r.get("inputs") or []:
                wanted.append((robot, label, tuple(inp.get("data") or ())))
        elif r.get("event") == "send" and r.get("channel"):
            channels.append(str(r["channel"]))
    for robot, label, data in wanted:
        source = produced.get((robot, data))
        if source is not None and source != label:
            channels.append((source, label, data))
    return configuration_of(fs.values(), channels)


UNKNOWN = math.nan
"""The cost of a configuration the trace does not give (a trace of emitted
programs, which do not know their configuration's cost): shown as ``?``."""


def _cost(value: object) -> float:
    return float(value) if isinstance(value, int | float) else UNKNOWN


def cost_text(config: Configuration) -> str:
    """A span's cost as the report writes it: ``44``, or ``?`` when the trace
    does not give it (never a made-up 0)."""
    return "?" if math.isnan(config.cost) else fmt(config.cost)


def _first_cost(records: Sequence[Record], switches: Sequence[Record]) -> float:
    """The cost of the configuration a run started with: the first switch's
    ``from_cost``, else the ``cost`` its robots' ``start`` events record."""
    if switches and switches[0].get("from_cost") is not None:
        return _cost(switches[0].get("from_cost"))
    until = float(switches[0]["t"]) if switches else math.inf
    costs = [
        float(r["cost"])
        for r in records
        if r.get("event") == "start"
        and float(r.get("t", 0)) <= until
        and isinstance(r.get("cost"), int | float)
    ]
    return costs[0] if costs else UNKNOWN


def from_records(
    records: Sequence[Record], summary: Record | None = None, origin: float | None = None
) -> Story:
    """The story of a trace (module docstring); times are seconds since ``origin``
    (by default the robots' start, else the first event)."""
    records = _unique(sorted(records, key=lambda r: float(r.get("t", 0))))
    starts = [float(r.get("t", 0)) for r in records if r.get("event") == "start"]
    first = float(records[0].get("t", 0)) if records else 0.0
    t0 = origin if origin is not None else min(starts) if starts else first
    simulated = summary is not None or t0 < 1e6  # a simulation's clock starts at 0
    robots: list[str] = []  # who wrote, who was a partner, who saw
    for r in records:
        for name in (r.get("robot"), *(r.get("partners") or []), r.get("detected_by")):
            if isinstance(name, str) and name and name not in robots:
                robots.append(name)
    end = max((float(r.get("t", 0)) - t0 for r in records), default=0.0)
    changes = [c for c in (summary or {}).get("world_changes") or [] if isinstance(c, dict)]
    end = max([end, *(float(c.get("time", 0)) for c in changes)])
    story = Story(
        title=str((summary or {}).get("title") or (summary or {}).get("scenario") or ""),
        robots=robots,
        end=end,
        clock="simulated time (s)" if simulated else "seconds since the run started",
    )
    # the configurations, switch by switch
    switches = [r for r in records if r.get("event") in ("switch", "no-configuration")]
    numbers: dict[object, int] = {}
    goal = ""
    steps_goals = [str(s.get("goal")) for s in (summary or {}).get("steps") or []]
    if steps_goals:
        goal = steps_goals[0]
    start = 0.0
    current: Configuration | None = None
    cost = _first_cost(records, switches)
    if switches and isinstance(switches[0].get("kept"), dict):
        current = configuration_of(*_parts(switches[0], "kept", "stopped"))
    elif switches and switches[0].get("from_cost") is not None:
        current = _from_calls(records, float(switches[0]["t"]))
    elif not switches:
        current = _from_calls(records, float("inf"))

    def close(until: float) -> None:
        if current is None:
            return
        key = _identity(current)
        number = numbers.setdefault(key, len(numbers) + 1)
        config = current.model_copy(update={"cost": cost})
        story.spans.append(Span(number, config, start, until, goal))

    for r in switches:
        t = float(r["t"]) - t0
        close(t)
        cause = str(r.get("cause") or "")
        if cause.startswith("next step: "):
            goal = cause.removeprefix("next step: ")
        if r.get("event") == "switch":
            fs, cs = _parts(r, "kept", "started")
            current = configuration_of(fs, cs) if fs else None
            cost = _cost(r.get("to_cost"))
        else:
            current = None
        start = t
        was = r.get("from_cost")
        to = r.get("to_cost") if r.get("event") == "switch" else "stop"
        text = f"{'nothing' if was is None else _num(was)} → {_num(to)}: {cause}"
        story.marks.append(Mark(t, str(r["event"]), text, "", r))
    close(end)
    for span in story.spans:  # robots only the configurations name
        robots += [a for a in span.config.agents if a not in robots]
    # failures and recoveries, on the row of the robot whose resource it is
    for r in records:
        what = r.get("event")
        if what not in ("failure", "recovery"):
            continue
        resource = str(r.get("resource") or "")
        row = owner(resource, robots, str(r.get("detected_by") or ""))
        text = f"{resource} fails" if what == "failure" else f"{resource} works again"
        story.marks.append(Mark(float(r["t"]) - t0, str(what), text, row, r))
    for c in changes:
        story.marks.append(Mark(float(c.get("time", 0)), "change", str(c.get("what", ""))))
    bar = (summary or {}).get("bar")
    if isinstance(bar, dict) and bar.get("dropped") and bar.get("dropped_at") is not None:
        story.marks.append(Mark(float(bar["dropped_at"]), "drop", "the bar falls"))
    story.marks.sort(key=lambda m: m.t)
    # the steps: the summary's, else the goals the switches name
    if summary is not None and summary.get("steps"):
        for s in summary["steps"]:
            done = s.get("time") if s.get("achieved") else None
            story.steps.append(Step(str(s.get("goal")), s.get("started"), done))
    else:
        achieved = [float(r["t"]) - t0 for r in records if r.get("event") == "achieved"]
        goals: list[tuple[str, float]] = [("", 0.0)]
        for r in switches:
            cause = str(r.get("cause") or "")
            if cause.startswith("next step: "):
                goals.append((cause.removeprefix("next step: "), float(r["t"]) - t0))
        for i, (g, t) in enumerate(goals):
            nxt = goals[i + 1][1] if i + 1 < len(goals) else None
            done = next((a for a in achieved if a >= t and (nxt is None or a <= nxt)), None)
            name = g or _first_goal(story) or "the task"
            story.steps.append(Step(name, t, done))
    return story


def _unique(records: list[Record]) -> list[Record]:
    """Without the copies several robots' traces hold: a switch by its id, a
    failure or recovery by its resource, how and detector within a second."""
    seen: dict[tuple[object, ...], float] = {}
    out = []
    for r in records:
        what = r.get("event")
        if what in ("switch", "no-configuration"):
            key: tuple[object, ...] = (what, r.get("id"), r.get("cause"))
        elif what in ("failure", "recovery"):
            key = (what, r.get("resource"), r.get("how"), r.get("detected_by"))
        else:
            out.append(r)
            continue
        t = float(r.get("t", 0))
        if key in seen and t - seen[key] < 1.0:
            continue
        seen[key] = t
        out.append(r)
    return out


def _first_goal(story: Story) -> str:
    """The action of the first configuration (a run's trace does not name its goal)."""
    if not story.spans:
        return ""
    config = story.spans[0].config
    sinks = [
        f for f in config.functionalities if not any(c.source == f.label for c in config.channels)
    ]
    return ", ".join(f"{f.name}({', '.join(f.args)})" for f in sinks)


def _num(value: object) -> str:
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)
