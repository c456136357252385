"""The live page's model: a pure function of a run's events (5.5).

:class:`Page` takes the events of the robots it is given (``Robot.subscribe``)
one at a time, in :meth:`Page.apply`, and keeps what the page shows:

* **inputs** — each functionality's input, by its label and data
  (``F3 pos(Emil, Door1)``), ``fresh``, ``waiting`` (no data yet) or
  ``stale`` (3.2), from the robot's calls and its ``stale`` / ``fresh``
  events, with the time of its last message; the diagram colours each
  channel by the input it feeds (several channels into one input share it);
* **robots** — ``running`` (its events arrive, or another robot sees it),
  ``lost``, ``stopped`` or ``unknown``, with its last cycle;
* **failed** — the resources that failed and have not recovered (``failure``
  and ``recovery`` events, 5.5);
* **coordinator** — the robot that decides the switches: the setup's, then
  whoever a ``takeover``, ``step-down`` or ``install`` event names (5.5);
* **timeline** — switches, failures, recoveries, state updates, injected
  faults, losses, coordination taken over or handed back and the like, each
  with its cause, in the words of the
  console (:func:`cfgplan.runtime.trace.notice`), the newest
  :attr:`Limits.timeline` kept.

:func:`model` folds a sequence of events into the page's JSON: the unit tests
drive it, and the server sends :meth:`Page.state` and
:meth:`Page.entries` as the page's server-sent events. Nothing here knows
about threads or the network.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from cfgplan.notation import call_text
from cfgplan.runtime.events import (
    STORY_KINDS,
    Adaptation,
    Call,
    Data,
    Event,
    Lifecycle,
    Presence,
    Staleness,
)
from cfgplan.runtime.events import Transfer as TransferEvent
from cfgplan.runtime.trace import notice

__all__ = ["TIMELINE_KINDS", "Limits", "Page", "Setup", "input_key", "model"]

TIMELINE_KINDS = frozenset(
    {*STORY_KINDS, "finish", "robot-seen", "robot-lost", "stop", "error", "takeover", "step-down"}
)
"""Events the timeline shows (``install`` too, on a robot that is not the coordinator)."""


def input_key(label: str, data: Data) -> str:
    """How the page names an input: ``F3 pos(Emil, Door1)``."""
    return f"{label} {call_text(data)}"


@dataclass(frozen=True)
class Limits:
    """How much the page keeps (a long run must not grow it)."""

    timeline: int = 300
    """Timeline entries kept, the newest."""
    text: int = 600
    """Characters of one entry's text or cause kept."""


@dataclass(frozen=True)
class Setup:
    """What the page knows before the first event."""

    title: str
    robots: tuple[str, ...]
    """The robots of the configuration (and of the state, if reconfiguring)."""
    here: tuple[str, ...]
    """The robots run in this process, whose events the page gets."""
    coordinator: str
    """The robot that decides the switches at the start
    (:func:`~cfgplan.reconfigure.local.coordinator_of`); the page follows
    whoever decides them later (:attr:`Page.coordinator`)."""
    cost: float | None = None
    """The first configuration's cost."""
    started: float = 0.0
    """When the run began (seconds since the epoch)."""


@dataclass
class Page:
    """The page's model, one event at a time (module docstring)."""

    setup: Setup
    limits: Limits = field(default_factory=Limits)
    version: int = 0
    """Increased by each change."""
    seq: int = 0
    """The number of the last timeline entry."""
    inputs: dict[str, dict[str, Any]] = field(default_factory=dict)
    robots: dict[str, dict[str, Any]] = field(default_factory=dict)
    failed: dict[str, dict[str, Any]] = field(default_factory=dict)
    timeline: deque[dict[str, Any]] = field(default_factory=deque)
    configuration: int = 0
    """The id of the running configuration (0: the first; a switch's id after)."""
    cost: float | None = None
    switches: int = 0
    halted: str | None = None
    """Why nothing runs (``no-configuration``), while nothing does."""
    coordinator: str = ""
    """The robot that decides the switches now: the setup's, then whoever took
    over (a ``takeover`` event of a robot here), was stepped down for
    (``step-down``), or whose switch a robot here installed (``install``)."""
    last: float = 0.0
    """The time of the newest event."""

    def __post_init__(self) -> None:
        self.cost = self.setup.cost
        self.coordinator = self.setup.coordinator
        for name in self.setup.robots:
            self.robots[name] = {"state": "unknown", "cycle": None, "t": None}

    # -- events -------------------------------------------------------------

    def apply(self, event: Event) -> None:
        """Take one event of a robot of this process."""
        self.version += 1
        self.last = max(self.last, event.t)
        self._alive(event.robot, event, own=True)
        if isinstance(event, Call):
            self._call(event)
        elif isinstance(event, Staleness):
            self._input(event.label, event.channel.data, event.state, event.t)
        elif isinstance(event, TransferEvent):
            key = input_key(event.channel.target, event.channel.data)
            entry = self.inputs.setdefault(key, {"state": "fresh", "t": event.t})
            entry["t"] = event.t
        elif isinstance(event, Presence):
            self._robot(event.other, "running" if event.alive else "lost", event.t)
        elif isinstance(event, Lifecycle) and event.what == "stop":
            self._robot(event.robot, "stopped", event.t)
        elif isinstance(event, Adaptation):
            self._adaptation(event)
        if event.kind in TIMELINE_KINDS or (event.kind == "install" and not self.decides):
            self._note(event)

    @property
    def decides(self) -> bool:
        """Whether the coordinator runs in this process (its switches are seen here)."""
        return self.coordinator in self.setup.here

    def _call(self, event: Call) -> None:
        if event.status == "ran":
            for data, _ in event.inputs:
                self._input(event.label, data, "fresh", event.t)
        for data in event.waiting:
            self._input(event.label, data, "waiting", event.t, keep=False)
        for data in event.stale:
            self._input(event.label, data, "stale", event.t, keep=False)

    def _input(self, label: str, data: Data, state: str, t: float, *, keep: bool = True) -> None:
        """Input ``data`` of ``label`` is in ``state``; ``keep``: the time of
        its last data moves on (it was read or refreshed)."""
        entry = self.inputs.setdefault(input_key(label, data), {"state": state, "t": None})
        entry["state"] = state
        if keep:
            entry["t"] = t

    def _alive(self, name: str, event: Event, *, own: bool) -> None:
        entry = self.robots.setdefault(name, {"state": "unknown", "cycle": None, "t": None})
        if own:
            entry["cycle"] = event.cycle
            entry["t"] = event.t
            if entry["state"] in ("unknown", "lost"):
                entry["state"] = "running"

    def _robot(self, name: str, state: str, t: float) -> None:
        entry = self.robots.setdefault(name, {"state": "unknown", "cycle": None, "t": None})
        entry["state"] = state
        entry["since"] = t

    def _adaptation(self, event: Adaptation) -> None:
        f = event.field
        what = event.what
        if what == "failure":
            resource = str(f("resource"))
            self.failed[resource] = {
                "kind": f("kind"),
                "how": f("how"),
                "t": event.t,
                "detail": self._clip(str(f("detail") or "")),
            }
            if f("kind") == "robot":
                self._robot(resource, "lost", event.t)
        elif what == "recovery":
            resource = str(f("resource"))
            self.failed.pop(resource, None)
            if f("kind") == "robot":
                self._robot(resource, "running", event.t)
        elif what == "switch":
            self.switches += 1
            self.configuration = _int(f("id"), self.configuration)
            to_cost = f("to_cost")
            self.cost = float(to_cost) if isinstance(to_cost, int | float) else None
            self.halted = None
        elif what == "takeover":
            self.coordinator = event.robot
        elif what in ("step-down", "install") and isinstance(f("leader"), str):
            self.coordinator = str(f("leader"))
        elif what == "no-configuration":
            self.configuration = _int(f("id"), self.configuration)
            self.cost = None
            why = f("why")
            self.halted = self._clip(
                "; ".join(map(str, why)) if isinstance(why, list) and why else str(f("cause"))
            )

    def _note(self, event: Event) -> None:
        try:
            text = notice(event) or event.kind
        except Exception:  # an event missing a field: the page must not stop the robots
            text = event.kind
        head = f"cycle {event.cycle}: {event.robot}"
        if text.startswith(head):
            text = text[len(head) :].lstrip(": ")
        self.seq += 1
        self.timeline.append(
            {
                "seq": self.seq,
                "t": event.t,
                "cycle": event.cycle,
                "robot": event.robot,
                "kind": event.kind,
                "text": self._clip(text),
                "cause": self._clip(_cause(event)),
            }
        )
        while len(self.timeline) > self.limits.timeline:
            self.timeline.popleft()

    def _clip(self, text: str) -> str:
        most = self.limits.text
        return text if len(text) <= most else text[: most - 1] + "…"

    # -- what the page gets ----------------------------------------------------

    def state(self) -> dict[str, Any]:
        """Everything the page shows but the timeline, as JSON-ready data."""
        return {
            "version": self.version,
            "title": self.setup.title,
            "coordinator": self.coordinator,
            "here": list(self.setup.here),
            "decides": self.decides,
            "started": self.setup.started,
            "last": self.last,
            "configuration": self.configuration,
            "cost": self.cost,
            "switches": self.switches,
            "halted": self.halted,
            "robots": {name: dict(entry) for name, entry in self.robots.items()},
            "inputs": {key: dict(entry) for key, entry in self.inputs.items()},
            "failed": {key: dict(entry) for key, entry in self.failed.items()},
        }

    def entries(self, after: int = 0) -> list[dict[str, Any]]:
        """The timeline entries numbered above ``after`` that are still kept."""
        return [dict(e) for e in self.timeline if e["seq"] > after]


def _int(value: object, default: int) -> int:
    return value if isinstance(value, int) else default


def _cause(event: Event) -> str:
    """Why it happened, where the event says."""
    if not isinstance(event, Adaptation):
        if isinstance(event, Lifecycle):
            info = dict(event.info)
            return str(info.get("why") or info.get("message") or "")
        return ""
    f = event.field
    if event.what in ("switch", "no-configuration"):
        return str(f("cause") or "")
    if event.what in ("failure", "recovery"):
        how, by = f("how"), f("detected_by")
        return f"{how}, seen by {by}" if by else str(how or "")
    if event.what == "abort":
        return str(f("reason") or "")
    if event.what == "facts":
        return str(f("how") or "")
    if event.what == "inject":
        return "scripted fault (--inject)"
    return ""


def model(events: Iterable[Event], setup: Setup, limits: Limits | None = None) -> dict[str, Any]:
    """The page's model after ``events``: its state, with the timeline under ``"timeline"``."""
    page = Page(setup, limits or Limits())
    for event in events:
        page.apply(event)
    return {**page.state(), "timeline": page.entries()}
