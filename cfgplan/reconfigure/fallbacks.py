"""Fallbacks ahead of time: the best configuration if one resource fails (5.5, 7.2).

For each resource the chosen configuration uses — each functionality
instance, each robot (or device) and each medium carrying one of its global
channels (4.6) — :func:`fallbacks` plans in the situation where that resource
alone has failed (:mod:`~cfgplan.reconfigure.situation`: the facts it
withdraws, the instance or robot kept out) and reports the cheapest
admissible configuration, or none with the planner's explanation. A resource
without fallback is a single point of failure. ``cfgplan plan --fallbacks``
prints the report; the reconfigurator keeps one for the configuration it
runs, so that a detected failure is answered without searching.

It mirrors what the thesis's operator did by hand: 6.2.2 step 3 (a compass
fails: the camera configuration, 47) and 6.3.2 (the laser fails: the two 45
configurations).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any, Literal

from cfgplan.configuration.describe import to_dict
from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import Medium
from cfgplan.notation import atom_text, call_text
from cfgplan.planner import plan
from cfgplan.planner.explain import explain
from cfgplan.planner.task import Ground, Task
from cfgplan.reconfigure.situation import Situation, derive
from cfgplan.reconfigure.switch import Change, change, highest_label, relabel

__all__ = ["Fallback", "Resource", "fallbacks", "medium_text", "outages", "resources"]


def medium_text(medium: Medium) -> str:
    """``medium(socket, Pippi, Emil, 200)`` as the state writes it (4.6)."""
    return f"medium({medium.type}, {medium.sender}, {medium.receiver}, {medium.capacity:g})"


@dataclass(frozen=True)
class Resource:
    """Something a configuration relies on that may fail."""

    kind: Literal["functionality", "robot", "medium"]
    instance: Ground = ()  # functionality: ("compass", "Emil")
    robot: str = ""  # robot (or device)
    medium: int = -1  # medium: index into the state's media
    text: str = field(default="", compare=False)  # how reports name it

    def fail(self, situation: Situation) -> Situation:
        """``situation`` with this resource failed."""
        if self.kind == "functionality":
            return situation.failing(self.instance)
        if self.kind == "robot":
            return situation.losing(self.robot)
        return situation.medium_down(self.medium)

    def recover(self, situation: Situation) -> Situation:
        """``situation`` with this resource working again (a robot back)."""
        if self.kind == "functionality":
            return situation.recovered(self.instance)
        if self.kind == "robot":
            return situation.returning(self.robot)
        return situation.medium_up(self.medium)


def resources(config: Configuration, media: tuple[Medium, ...]) -> list[Resource]:
    """Functionality instances (the configuration's order), robots and
    devices (order of first appearance), then media carrying its channels."""
    out = [
        Resource("functionality", instance=f.key, text=call_text(f.key))
        for f in config.functionalities
    ]
    out += [Resource("robot", robot=r, text=r) for r in config.agents]
    used = dict.fromkeys(a.medium for a in config.media)
    out += [Resource("medium", medium=i, text=medium_text(media[i])) for i in used]
    return out


def outages(situation: Situation, media: tuple[Medium, ...]) -> list[Resource]:
    """What is out of service in ``situation``: robots lost, functionality
    instances failed, media down (each of which may come back)."""
    out = [Resource("robot", robot=r, text=r) for r in situation.lost]
    out += [Resource("functionality", instance=f, text=call_text(f)) for f in situation.failed]
    out += [Resource("medium", medium=i, text=medium_text(media[i])) for i in situation.media_down]
    return out


@dataclass(frozen=True)
class Fallback:
    """What to run if ``resource`` fails: ``config`` (relabelled to keep the
    running labels) and the ``change`` from the running one, or ``None`` and
    ``why`` (the planner's explanation)."""

    resource: Resource
    withdrawn: tuple[Ground, ...]
    config: Configuration | None
    change: Change | None
    why: tuple[str, ...] = ()
    proven: bool = True  # False: a time limit cut the search before it proved the answer

    def record(self, media: tuple[Medium, ...] = ()) -> dict[str, Any]:
        """One entry of ``"fallbacks"`` in ``cfgplan plan --format json``."""
        c = self.config
        return {
            "resource": self.resource.text,
            "kind": self.resource.kind,
            "withdrawn": [atom_text(f) for f in self.withdrawn],
            "cost": None if c is None else to_dict(c, 1)["cost"],
            "robots": None if c is None else c.robots,
            "stopped": []
            if self.change is None
            else [call_text(f.key) for f in self.change.stopped],
            "started": []
            if self.change is None
            else [call_text(f.key) for f in self.change.started],
            "configuration": None if c is None else _configuration(c),
            "why": list(self.why) if c is None else None,
            "proven": self.proven,
        }


@dataclass
class Prepared:
    """The fallbacks computed ahead of time, by the situation they were
    computed in and the resource whose failure they answer, for the
    ``situations`` last stored in only: a long run meets ever new situations
    (each failure, recovery and update is one), and a fallback is looked up
    only in the situation it was computed in (a recovery may return to one
    met shortly before). A fallback of ``None``: nothing is admissible then."""

    situations: int
    _by: OrderedDict[Situation, dict[Resource, Configuration | None]] = field(
        default_factory=OrderedDict
    )

    def get(self, situation: Situation, resource: Resource) -> tuple[bool, Configuration | None]:
        """Whether the fallback is known, and what it is."""
        found = self._by.get(situation, {})
        return resource in found, found.get(resource)

    def put(self, situation: Situation, resource: Resource, config: Configuration | None) -> None:
        """Keep a fallback; forget those of the situation stored in longest
        ago when more than ``situations`` have some."""
        found = self._by.setdefault(situation, {})
        self._by.move_to_end(situation)
        found[resource] = config
        while len(self._by) > self.situations:
            self._by.popitem(last=False)

    def clear(self) -> None:
        """Forget every fallback (they were for another goal)."""
        self._by.clear()

    def __len__(self) -> int:
        return sum(map(len, self._by.values()))


def _configuration(config: Configuration) -> dict[str, Any]:
    entry = to_dict(config, 1)
    del entry["rank"]
    return entry


def fallback(
    task: Task,
    goal: Ground,
    config: Configuration,
    resource: Resource,
    situation: Situation | None = None,
    *,
    after: Situation | None = None,
    derived: Task | None = None,
    time_limit: float | None = None,
) -> Fallback:
    """The best configuration when ``resource`` fails on top of ``situation``
    (``after``: the situation it gives, if the caller knows better, e.g. with
    a lowered reliability; ``derived``: its task, if the caller keeps one;
    ``time_limit``: seconds for the search, and again for the explanation)."""
    before = situation or Situation()
    after = resource.fail(before) if after is None else after
    found, search = plan(
        derive(task, after) if derived is None else derived,
        goal,
        limit=1,
        time_limit=time_limit,
    )
    proven = not search.status.stopped and all(c.proven for c in found)
    withdrawn = tuple(f for f in after.withdrawn(task) if f not in before.withdrawn(task))
    if not found:
        why = explain(search.report, call_text(goal))
        return Fallback(resource, withdrawn, None, None, tuple(why), proven)
    best = _media_indexes(found[0], task, after)
    best = relabel(best, config, highest_label([config, best]) + 1)
    return Fallback(resource, withdrawn, best, change(config, best), (), proven)


def _media_indexes(config: Configuration, task: Task, situation: Situation) -> Configuration:
    """Media assignments as indexes into the state's media (the derived task
    lists only the media that are up)."""
    if not situation.media_down:
        return config
    up = [i for i in range(len(task.media)) if i not in situation.media_down]
    media = tuple(a.model_copy(update={"medium": up[a.medium]}) for a in config.media)
    return config.model_copy(update={"media": media})


def fallbacks(
    task: Task,
    goal: Ground,
    config: Configuration,
    situation: Situation | None = None,
    time_limit: float | None = None,
) -> list[Fallback]:
    """A :class:`Fallback` for every resource of ``config`` (:func:`resources`),
    each search given ``time_limit`` seconds (``None``: no limit)."""
    return [
        fallback(task, goal, config, r, situation, time_limit=time_limit)
        for r in resources(config, task.media)
    ]
