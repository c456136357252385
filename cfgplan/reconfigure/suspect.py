"""Stale inputs as suspicions of their senders, acted on once settled (5.5).

A **stale** input suspects the functionality that feeds it. The suspicion
must *settle*: it is acted on only if no ``fresh`` withdraws it within the
staleness limit of that channel (so a new configuration's first cycles, when
data is not yet flowing, are not mistaken for a failure), and only against
the most upstream suspects: a functionality whose own inputs come, directly
or not, from another suspect is starved, not failed (staleness flows
downstream), and its suspicion's clock starts only once nothing upstream
of it is suspected any more (fed again, it needs a cycle to send: the
upstream's ``fresh`` and its own may arrive in two messages, and between
them it must not look failed). :class:`Suspicions` keeps them for the
:class:`~cfgplan.reconfigure.coordinate.Coordinator`.

**Blame what failed** (5.5): a functionality is suspected only on
evidence about *it*. When every channel from one robot into another is stale
at once, nothing tells a silent computation from a silent robot or a link
that stalls (a lost packet is retransmitted after 200 ms or more: at 10 %
loss, inputs go stale every few seconds): the suspicion then waits
:attr:`Suspicions.grace` — the robot's lease (liveliness) decides first, and
the link gets time to catch up — and is acted on only if data has not come
back by then. When another channel from the same robot still flows, the
suspect's own outputs stopped: it is acted on at its staleness limit, or,
when another robot saw it, after :attr:`Suspicions.reported` at least (its
reports cross the same lossy network).

**A robot that stood still** (:mod:`cfgplan.reconfigure.stall`): when the
coordinator's own process stopped a while, the inputs it reads and the
outputs it sends went stale *because of that*: the other robots' reports of
its silent outputs, and its own stale inputs, arrive as it runs again, and
the fresh data after them may take the network a while. :meth:`Suspicions.excuse`
holds every suspicion that robot is part of (as the robot whose data stopped
or as the one that saw it) unripe until a deadline, as a starved one is:
its clock starts again then, so a functionality that really stopped is
still blamed, one staleness limit later.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from cfgplan.configuration.model import Configuration
from cfgplan.planner.task import Ground
from cfgplan.reconfigure.situation import Situation
from cfgplan.runtime.monitor import Detection, doubled_hold

__all__ = ["SILENT_LINK", "Blamed", "Suspicions", "upstream"]

SILENT_LINK = "silent link"
"""How a failure blamed past the grace on a link whose every channel was
stale is said: it is tried again after the plain hold, never a doubled one
(the link, not the computation, was silent)."""


def upstream(config: Configuration, label: str) -> set[str]:
    """Labels whose data reaches ``label`` through the configuration's channels."""
    feeds: dict[str, set[str]] = {}
    for c in config.channels:
        feeds.setdefault(c.target, set()).add(c.source)
    seen: set[str] = set()
    todo = list(feeds.get(label, ()))
    while todo:
        current = todo.pop()
        if current not in seen:
            seen.add(current)
            todo.extend(feeds.get(current, ()))
    return seen


@dataclass
class _Suspicion:
    since: float  # monotonic
    limit: float
    detection: Detection


@dataclass
class Suspicions:
    """The open suspicions, by (robot, label, channel detail)."""

    clock: Callable[[], float] = time.monotonic
    grace: float = 0.0
    """Seconds a suspicion waits when every channel from its sender's robot
    into the robot that saw it is stale (module docstring); 0: no wait (robots
    of one process share no link to blame)."""
    here: str = ""
    """The coordinator's robot: what it saw itself took no network to learn."""
    reported: float = 0.0
    """Seconds a suspicion another robot reported waits at least: its stale
    and its fresh cross the network, and a lost packet delays the one after
    the other by 200 ms or more (0: no wait)."""
    _open: dict[tuple[str, str, str], _Suspicion] = field(default_factory=dict)
    _excused: dict[str, float] = field(default_factory=dict)  # robot -> until (clock)

    def note(self, detection: Detection) -> None:
        """A ``stale`` detection opens (or renews) a suspicion; ``fresh`` withdraws it."""
        key = (detection.robot, detection.label, detection.detail)
        if detection.kind == "fresh":
            self._open.pop(key, None)
        else:
            self._open[key] = _Suspicion(self.clock(), detection.limit, detection)

    def clear(self) -> None:
        """Forget them all (a switch is being deployed)."""
        self._open.clear()

    def excuse(self, robot: str, until: float) -> None:
        """``robot`` stood still (module docstring): no suspicion it is part
        of ripens before ``until`` (this clock's time); each one's clock
        starts again then."""
        self._excused[robot] = max(until, self._excused.get(robot, until))
        now = self.clock()
        for gone in [r for r, deadline in self._excused.items() if deadline <= now]:
            del self._excused[gone]

    def _excuses(self, detection: Detection, now: float) -> float:
        """When the excuses of the robots ``detection`` involves run out
        (``now`` or earlier when none is excused)."""
        involved = (detection.robot, detection.other)
        return max([now, *(self._excused.get(r, now) for r in involved if r)])

    def settled(self, running: Configuration | None) -> Detection | None:
        """The ``failure`` to act on: the most upstream suspect of ``running``
        that stayed stale past its limit (the first by label), whose
        suspicions are then closed; None while none has settled."""
        if running is None or not self._open:
            self._open.clear()
            return None
        labels = {f.label: f for f in running.functionalities}
        now = self.clock()
        for key in [k for k, s in self._open.items() if s.detection.label not in labels]:
            del self._open[key]  # a channel of an earlier configuration
        suspected = {s.detection.label for s in self._open.values()}
        for suspicion in self._open.values():
            if upstream(running, suspicion.detection.label) & suspected:
                suspicion.since = now  # starved, not failed: its clock runs once fed again
            excused = self._excuses(suspicion.detection, now)
            if excused > now:  # stale because a robot stood still: its clock runs from then
                suspicion.since = max(suspicion.since, excused)
        silent = self._silent_links(running)
        ripe = {
            s.detection.label: s
            for s in self._open.values()
            if now - s.since >= self._wait(s, silent)
        }
        roots = [label for label in ripe if not (upstream(running, label) & suspected)]
        if not roots:
            return None
        label = sorted(roots)[0]
        suspicion = ripe[label]
        for key in [k for k in self._open if k[1] == label]:
            del self._open[key]
        link = self.grace > 0 and (suspicion.detection.other, suspicion.detection.robot) in silent
        waited = self._wait(suspicion, silent)
        return Detection(
            "failure",
            suspicion.detection.robot,
            suspicion.detection.t,
            instance=labels[label].key,
            label=label,
            other=suspicion.detection.other,  # the robot whose data stopped
            how=SILENT_LINK if link else "stale",
            detail=f"input {suspicion.detection.detail} stale for over {waited:g} s",
        )

    def _silent_links(self, running: Configuration) -> set[tuple[str, str]]:
        """The (sender, receiver) robot pairs every channel of which is suspected."""
        suspected = {
            (s.detection.other, s.detection.robot, s.detection.label) for s in self._open.values()
        }
        links: dict[tuple[str, str], set[str]] = {}
        for c in running.channels:
            if c.kind == "global" and c.source_robot != c.target_robot:
                links.setdefault((c.source_robot, c.target_robot), set()).add(c.source)
        return {
            link
            for link, sources in links.items()
            if all((*link, source) in suspected for source in sources)
        }

    def _wait(self, suspicion: _Suspicion, silent: set[tuple[str, str]]) -> float:
        """How long ``suspicion`` must stay open to be acted on."""
        link = (suspicion.detection.other, suspicion.detection.robot)
        wait = suspicion.limit
        if link in silent:
            wait = max(wait, self.grace)
        if suspicion.detection.robot != self.here:
            wait = max(wait, self.reported)
        return wait


@dataclass(frozen=True)
class _Blame:
    """Why and since when a functionality instance is out for stale outputs."""

    sender: str  # the robot whose data stopped
    since: float  # when it was blamed (the coordinator's clock)
    hold: float  # how long before it is tried again


@dataclass
class Blamed:
    """The functionality instances failed only because their outputs went
    stale (:meth:`Suspicions.settled`): a silent robot looks at first like a
    silent computation on it, so these come back on evidence about the robot
    (5.5): it is seen again (:meth:`silenced_by`), or its hold is over while
    it is not lost (:meth:`due`); each blame of the same instance doubles its
    hold, up to :data:`~cfgplan.runtime.monitor.HOLD_MAX`."""

    hold: float
    _out: dict[Ground, _Blame] = field(default_factory=dict)
    _times: dict[Ground, int] = field(default_factory=dict)

    def blame(self, instance: Ground, sender: str, now: float, *, doubling: bool = True) -> None:
        """``instance`` failed at ``now`` because ``sender``'s data stopped; not
        ``doubling``: on no evidence about it (a silent link), tried again
        after the plain hold each time."""
        times = self._times[instance] = self._times.get(instance, 0) + 1
        hold = doubled_hold(self.hold, times) if doubling else self.hold
        self._out[instance] = _Blame(sender, now, hold)

    def forget(self, instance: Ground) -> None:
        """``instance`` recovered (its count of blames stays, for the next hold)."""
        self._out.pop(instance, None)

    def silenced_by(self, robot: str, situation: Situation) -> list[Ground]:
        """What is still out because ``robot``'s data stopped."""
        return [i for i, b in self._out.items() if b.sender == robot and i in situation.failed]

    def due(self, situation: Situation, now: float) -> list[Ground]:
        """What is still out, its hold over, the robot whose data stopped not lost."""
        return [
            i
            for i, b in self._out.items()
            if i in situation.failed and b.sender not in situation.lost and now - b.since >= b.hold
        ]
