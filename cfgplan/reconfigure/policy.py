"""Deciding what to run after a failure, a recovery or a state update (5.5, 7.2).

The :class:`Reconfigurator` keeps the situation (what has failed, what came
back, what the operator changed, :mod:`~cfgplan.reconfigure.situation`) and
the configuration the society runs, and answers each change with a
:class:`Decision`:

* **a resource the running configuration uses fails** (a functionality
  instance, a robot): the configuration is inadmissible, so the society
  must switch — to the fallback computed ahead of time for that resource
  (no search: :meth:`Reconfigurator.prepare` computes them one by one, or
  :class:`~cfgplan.reconfigure.ahead.Ahead` on a thread of its own),
  else to the cheapest configuration of a search on the derived task (no
  cold start: the domain is not read, checked or compiled again). If none
  is admissible, the configuration is *stopped* (the action halts) and the
  planner's explanation says why;
* **a resource it does not use fails**: the state changes, the
  configuration stays, unless it relies on something else out of service
  (a configuration rolled back to after an aborted switch may,
  :meth:`~cfgplan.reconfigure.situation.Situation.breaks`): then the
  society switches as for a failure it uses;
* **a resource comes back, or the operator adds or removes facts**: the
  cheapest configuration is planned again; the society switches to it only
  when the running configuration is no longer derivable (the operator
  removed what it needs) or when the gain is worth a switch
  (:class:`Hysteresis`); a stopped society resumes as soon as anything is
  admissible;
* **an action's task is accomplished**: its configuration's postconditions
  (4.5: P) become true and the configuration is played out (6.2.2); in a
  sequence of configurations (``goals`` after the current one), the next
  step's configuration takes over.

In a sequence, every choice — the next step's configuration, a switch after a
failure — is the first step of the cheapest sequence of the remaining goals
from the current state (:mod:`cfgplan.planner.sequence`), so a failure in a
step re-plans the steps after it too; fallbacks ahead of time, which know one
goal only, are not used then.

Every failure of a functionality instance also multiplies its reliability
(7.2) by ``decay`` for later choices: with ``--weights reliability=W`` a
resource that failed costs ``W·(−ln decay)`` more each time, so a flaky
sensor is chosen again only when it is clearly worth it.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Literal

from cfgplan.backends.part import runtime_part
from cfgplan.backends.wiring import deploy
from cfgplan.configuration.model import Configuration
from cfgplan.ir.model import Domain
from cfgplan.notation import call_text
from cfgplan.planner import plan
from cfgplan.planner.explain import explain
from cfgplan.planner.sequence import SequenceSearch
from cfgplan.planner.task import Ground, Task
from cfgplan.reconfigure.decision import Decision, Hysteresis
from cfgplan.reconfigure.fallbacks import Prepared, Resource, fallback, outages, resources
from cfgplan.reconfigure.situation import Situation, derive
from cfgplan.reconfigure.switch import change, highest_label, relabel
from cfgplan.runtime.part import Part

__all__ = ["Reconfigurator"]


TASKS_KEPT = 8
"""Derived tasks a :class:`Reconfigurator` keeps, the most recently used: the
current situation's, and those a recovery may return to; its fallbacks are
kept for as many situations, those last stored in (:class:`Prepared`)."""


@dataclass
class Reconfigurator:
    """The planning side of a running society (module docstring)."""

    task: Task
    domain: Domain
    goal: Ground
    running: Configuration | None
    hysteresis: Hysteresis = field(default_factory=Hysteresis)
    goals: tuple[Ground, ...] = ()
    """The goals of the steps after the current one (a sequence, 7.3)."""
    situation: Situation = field(default_factory=Situation)
    id: int = 0
    next_label: int = 0
    _tasks: OrderedDict[Situation, Task] = field(default_factory=OrderedDict)
    _fallbacks: Prepared = field(default_factory=lambda: Prepared(TASKS_KEPT))
    _pending: list[tuple[Situation, Resource]] = field(default_factory=list)
    _returns: list[Situation] = field(default_factory=list)
    """Situations a recovery of what is out now returns to, still to look at
    (:meth:`look_ahead`)."""
    _bests: OrderedDict[Situation, tuple[Configuration | None, tuple[str, ...]]] = field(
        default_factory=OrderedDict
    )
    """The cheapest configuration of situations looked at ahead, and why there
    is none: what the recovery that returns to one decides by, with no search."""
    _queued: int = 0  # the lists' generation: a new decision makes them anew
    _played: Configuration | None = None
    """The configuration whose task was accomplished last (6.2.2): should the
    switch to the next step not be deployed, the society runs it again, and
    it serves no goal any longer."""
    lock: threading.Lock = field(default_factory=threading.Lock)
    """Guards the fallbacks, which :mod:`~cfgplan.reconfigure.ahead` computes on a thread."""

    def __post_init__(self) -> None:
        self.next_label = highest_label([self.running]) + 1
        self._queue_fallbacks()

    # -- the situation -----------------------------------------------------

    def derived(self, situation: Situation | None = None) -> Task:
        """The task of ``situation`` (default: the current one), derived once
        while it is among the :data:`TASKS_KEPT` last used (each task keeps
        its grounding and bounds: a long run meets ever new situations)."""
        s = self.situation if situation is None else situation
        found = self._tasks.get(s)
        if found is None:
            found = self._tasks[s] = derive(self.task, s)
            if len(self._tasks) > TASKS_KEPT:
                self._tasks.popitem(last=False)
        self._tasks.move_to_end(s)
        return found

    def _failing(self, situation: Situation, resource: Resource) -> Situation:
        after = resource.fail(situation)
        if resource.kind == "functionality":
            schema = self.task.functionality(resource.instance)
            if schema is not None:
                p = dict(situation.reliability).get(
                    resource.instance,
                    self.task.functionality_reliability(schema, resource.instance),
                )
                after = after.with_reliability(resource.instance, p * self.hysteresis.decay)
        return after

    # -- fallbacks ahead of time --------------------------------------------

    def _queue_fallbacks(self) -> None:
        """The running configuration's fallbacks to compute, then the
        situations each recovery of what is out returns to, to look at."""
        with self.lock:
            running, situation = self.running, self.situation
            self._queued += 1
            if running is None or self.goals:  # see the module docstring
                self._pending, self._returns = [], []
                return
            media = self.task.media
            self._pending = [(situation, r) for r in resources(running, media)]
            self._returns = [r.recover(situation) for r in outages(situation, media)]

    def next_fallback(self) -> tuple[Situation, Configuration, Resource] | None:
        """The next fallback of the running configuration still to compute
        (taken off the list), or ``None``: those of the current situation,
        then those of a situation a recovery returns to (:meth:`look_ahead`)."""
        with self.lock:
            while self._pending and self.running is not None:
                situation, resource = self._pending.pop(0)
                if not self._fallbacks.get(situation, resource)[0]:
                    return situation, self.running, resource
            return None

    def look_ahead(self, time_limit: float | None = None) -> bool:
        """Plan the next situation a recovery returns to (a robot lost comes
        back, a failed instance works again): its cheapest configuration is
        kept for that recovery's decision, and if the running configuration
        would stay there (:meth:`_keeps`: nothing cheaper worth a switch),
        its fallbacks in that situation are queued. So a recovery that
        switches nothing finds every fallback ready for the next failure, as
        a switch does: computed while what recovers was out (a recovery that
        queued them anew left the next failure to a search, 38-154 ms at 50
        robots, if it came within a few hundred milliseconds). Safe on
        another thread (a task of its own); a search cut by ``time_limit``
        keeps nothing. Whether there was a situation to look at."""
        with self.lock:
            running = self.running
            if not self._returns or running is None:
                return False
            situation, queued = self._returns.pop(0), self._queued
        best, why, proven = self._cheapest(derive(self.task, situation), time_limit)
        with self.lock:
            if not proven or queued != self._queued:  # cut, or a decision since
                return True
            self._bests[situation] = (best, why)
            self._bests.move_to_end(situation)
            while len(self._bests) > TASKS_KEPT:
                self._bests.popitem(last=False)
            if self._valid(running, situation, still_valid=True) and self._keeps(running, best):
                self._pending += [(situation, r) for r in resources(running, self.task.media)]
        return True

    def compute(
        self,
        situation: Situation,
        running: Configuration,
        resource: Resource,
        time_limit: float | None = None,
    ) -> None:
        """Plan the fallback for ``resource`` failing in ``situation`` and keep
        it (safe on another thread: it plans a task of its own). A search cut
        by ``time_limit`` before it proved anything keeps nothing."""
        after = self._failing(situation, resource)
        found = fallback(
            self.task,
            self.goal,
            running,
            resource,
            situation,
            after=after,
            derived=derive(self.task, after),
            time_limit=time_limit,
        )
        if found.proven:
            with self.lock:
                self._fallbacks.put(situation, resource, found.config)

    def prepare(self) -> bool:
        """Compute one fallback of the running configuration now (in idle
        time); whether more remain."""
        job = self.next_fallback()
        if job is not None:
            self.compute(*job)
        else:
            self.look_ahead()
        with self.lock:
            return bool(self._pending or self._returns)

    def fallback(
        self, situation: Situation, resource: Resource
    ) -> tuple[bool, Configuration | None]:
        """Whether the fallback for ``resource`` in ``situation`` is known, and what it is."""
        with self.lock:
            return self._fallbacks.get(situation, resource)

    # -- changes ------------------------------------------------------------

    def failed(
        self, resource: Resource, cause: str = "", together: tuple[Resource, ...] = ()
    ) -> Decision:
        """``resource`` failed (or a robot was lost), and with it ``together``
        (robots silent in one switch): one decision for all."""
        before = self.situation
        after = self._failing(before, resource)
        for other in together:
            after = self._failing(after, other)
        self.situation = after
        withdrawn = tuple(
            f for f in self.situation.withdrawn(self.task) if f not in before.withdrawn(self.task)
        )
        if self.running is None or (
            not self.situation.breaks(self.running) and self.running is not self._played
        ):
            # Not used (and nothing else of it out: after an aborted switch,
            # the configuration rolled back to may rely on a failure).
            return self._stay(cause, withdrawn)
        started = time.perf_counter()
        if self.goals or together:  # fallbacks are planned for one failure each
            known, best = False, None
        else:
            known, best = self.fallback(before, resource)
        source: Literal["fallback", "search"] = "fallback" if known else "search"
        why: tuple[str, ...] = ()
        if not known or best is None:
            best, why = self._best()
        return self._to(best, source, time.perf_counter() - started, why, withdrawn, cause)

    def recovered(
        self, resource: Resource, cause: str = "", together: tuple[Resource, ...] = ()
    ) -> Decision:
        """``resource`` works again (or a robot is back), and with it
        ``together``: one decision for all."""
        for each in (resource, *together):
            self.situation = each.recover(self.situation)
        return self._better(cause, still_valid=True)

    def updated(
        self, add: tuple[Ground, ...], remove: tuple[Ground, ...], cause: str = ""
    ) -> Decision:
        """The operator (or a postcondition) added and removed facts."""
        self.situation = self.situation.updated(add, remove)
        return self._better(cause, still_valid=not remove)

    def achieved(self) -> Decision:
        """The action's task is accomplished: P becomes true, the configuration
        is played out (6.2.2)."""
        config = self._played = self.running
        add: list[Ground] = []
        remove: list[Ground] = []
        for text in () if config is None else config.postconditions:
            words = text.replace("(", " ").replace(")", " ").split()
            if words and words[0] == "not":
                remove.append(tuple(words[1:]))
            elif words:
                add.append(tuple(words))
        self.situation = self.situation.updated(add, remove)
        if not self.goals:
            return self._to(None, "", 0.0, ("the task is accomplished",), (), "achieved")
        self.goal, self.goals = self.goals[0], self.goals[1:]
        with self.lock:
            self._fallbacks.clear()  # they were for the goal of the step before
            self._bests.clear()
        started = time.perf_counter()
        best, why = self._best()
        cause = f"next step: {call_text(self.goal)}"
        return self._to(best, "search", time.perf_counter() - started, why, (), cause)

    def replanned(self, cause: str = "") -> Decision:
        """The cheapest configuration of the current step in the current
        situation, whatever runs (a robot that takes over coordination knows
        nothing running, 5.5); none: the society stops, and why."""
        started = time.perf_counter()
        best, why = self._best()
        return self._to(best, "search", time.perf_counter() - started, why, (), cause)

    def install(self, config: Configuration | None, cause: str = "") -> Decision:
        """Run ``config`` next (``None``: nothing), whatever it costs: the
        running labels kept for what both share, fresh ones for the rest.
        For sequences of configurations (7.3): each step installs the next."""
        started = time.perf_counter()
        return self._to(config, "", time.perf_counter() - started, (), (), cause)

    def rollback(self, previous: Configuration | None) -> None:
        """A switch could not be deployed: the society still runs ``previous``
        (should it be the step just accomplished, the next failure, recovery
        or update switches to the current step whatever it breaks)."""
        self.running = previous
        self._queue_fallbacks()

    # -- helpers ------------------------------------------------------------

    def _best(self) -> tuple[Configuration | None, tuple[str, ...]]:
        """The cheapest configuration in the current situation (looked at ahead
        already, or planned now), or why there is none."""
        if self.goals:
            return self._first_step()
        with self.lock:
            ahead = self._bests.get(self.situation)
        if ahead is not None:
            return ahead
        best, why, _ = self._cheapest(self.derived())
        return best, why

    def _cheapest(
        self, task: Task, time_limit: float | None = None
    ) -> tuple[Configuration | None, tuple[str, ...], bool]:
        """The cheapest configuration of ``task`` for the goal, or why there is
        none, and whether the search proved it (no ``time_limit`` cut it)."""
        found, search = plan(task, self.goal, limit=1, time_limit=time_limit)
        proven = not search.status.stopped and all(c.proven for c in found)
        if found:
            return found[0], (), proven
        return None, tuple(explain(search.report, call_text(self.goal))), proven

    def _first_step(self) -> tuple[Configuration | None, tuple[str, ...]]:
        """The current step's configuration in the cheapest sequence of the
        remaining goals from the current state; else why there is none."""
        goals = (self.goal, *self.goals)
        search = SequenceSearch(goals, self.derived())
        best = next(iter(search), None)
        if best is not None:
            return best.steps[0].configuration, ()
        blocked = search.blocked()
        if blocked is None:
            return None, ("no admissible sequence of the remaining steps",)
        step, _, report = blocked
        head = f"step {step + 1} of the remaining ones, {call_text(goals[step])}, is impossible"
        return None, (head, *explain(report, call_text(goals[step])))

    def _better(self, cause: str, still_valid: bool) -> Decision:
        started = time.perf_counter()
        best, why = self._best()
        seconds = time.perf_counter() - started
        running = self.running
        if running is None:
            if best is None:
                return self._stay(cause)
            return self._to(best, "search", seconds, (), (), cause)
        if not self._valid(running, self.situation, still_valid):
            return self._to(best, "search", seconds, why, (), cause)
        if self._keeps(running, best):
            return self._stay(cause)
        return self._to(best, "search", seconds, (), (), cause)

    def _valid(self, running: Configuration, situation: Situation, still_valid: bool) -> bool:
        """Whether ``running`` may run on in ``situation``: not played out, not
        relying on anything out of service, and derivable (``still_valid``:
        known to be, nothing it needs was removed; else planned again in the
        current situation, on the robots' thread only)."""
        return (
            running is not self._played
            and (still_valid or self._derivable(running))
            and not situation.breaks(running)
        )

    def _keeps(self, running: Configuration, best: Configuration | None) -> bool:
        """Whether the society stays on ``running`` (valid) when ``best`` is the
        cheapest: it is the same, or not cheaper by enough (:class:`Hysteresis`)."""
        if best is None or best.identity() == running.identity():
            return True
        return not self.hysteresis.worth(running.cost, best.cost)

    def _derivable(self, config: Configuration, most: int = 1024) -> bool:
        """Whether the planner still finds ``config`` in the current situation."""
        limit = 4
        while True:
            found, search = plan(self.derived(), self.goal, limit=limit)
            if any(c.identity() == config.identity() for c in found):
                return True
            if search.status.exhausted or len(found) < limit or limit >= most:
                return False
            limit *= 4

    def _stay(self, cause: str, withdrawn: tuple[Ground, ...] = ()) -> Decision:
        """Run on as before. The situation may have changed though (a failure
        of what is not used, a recovery not worth a switch), and fallbacks
        are kept by situation: those of the new one are queued, so that the
        next failure is still answered by one (those known are skipped)."""
        self._queue_fallbacks()
        return Decision(
            "stay", self.id, self.running, self.running, withdrawn=withdrawn, cause=cause
        )

    def _to(
        self,
        best: Configuration | None,
        source: Literal["fallback", "search", ""],
        seconds: float,
        why: tuple[str, ...],
        withdrawn: tuple[Ground, ...],
        cause: str,
    ) -> Decision:
        previous = self.running
        if best is not None:
            best = relabel(best, previous, self.next_label)
            self.next_label = max(self.next_label, highest_label([best]) + 1)
        self.id += 1
        with self.lock:
            self.running = best
        self._queue_fallbacks()
        return Decision(
            "switch" if best is not None else "stop",
            self.id,
            best,
            previous,
            change(previous, best),
            source,
            seconds,
            why,
            withdrawn,
            cause,
        )

    def parts(self, previous: Configuration | None = None) -> dict[str, Part]:
        """The running configuration per robot (sorted, divided and wired,
        5.1–5.3); robots of ``previous`` not in it get an empty part."""
        out: dict[str, Part] = {}
        if self.running is not None:
            for robot_part in deploy(self.running, self.domain):
                part = runtime_part(robot_part)
                out[part.robot] = part
        if previous is not None:
            for agent in previous.agents:
                out.setdefault(agent, Part(agent, (), ()))
        return out
