"""What the society committed, on the wire: the situation a successor plans from (5.5, 7.2).

The coordinator learns, as the society runs, what changed since the state was
read (:class:`~cfgplan.reconfigure.situation.Situation`): the operator's
state updates, the postconditions of the steps accomplished (4.5), the
functionality instances out of service, the media down, the reliabilities
lowered by failures (7.2). A robot that takes over coordination
(:mod:`~cfgplan.reconfigure.succession`) knows only the state it was started
with, unless it is told: so the coordinator tells every robot that is ready
what the society knows, once nothing is in flight — after each commit, and
after each change that needed no switch — as a
:class:`~cfgplan.runtime.protocol.State` (:func:`state_of`); each robot keeps
the last one of the run it follows
(:attr:`~cfgplan.runtime.member.Member.known`), and a robot that takes over
plans from it (:func:`situation_of`). What the old coordinator learnt while a
switch was in flight, and had not committed when it died, is not known.

Not carried: the robots lost. Who is in the society is each coordinator's own
liveliness view: the successor takes the coordinator gone as lost, greets
every robot alive, and finds a robot the configuration needs that does not
run when it deploys.

A :class:`State` comes from another process: the protocol checks its shape
and bounds (:data:`~cfgplan.runtime.protocol.MAX_FACTS` entries a list,
names of at most :data:`~cfgplan.runtime.protocol.MAX_NAME` characters,
reliabilities above 0 and at most 1); :func:`situation_of` checks it against
the task and drops what the task does not know, saying why: a fact whose
predicate starts with ``:`` (the situation's own guard facts, which no
domain or state can write), an instance of no functionality of the domain, a
medium the state does not declare.
"""

from __future__ import annotations

from cfgplan.planner.task import Ground, Task
from cfgplan.reconfigure.situation import Situation
from cfgplan.runtime.errors import printable
from cfgplan.runtime.protocol import MAX_FACTS, State, clip

__all__ = ["situation_of", "state_of"]


def state_of(situation: Situation, id: int, sender: str, epoch: str, step: int) -> State | None:
    """``situation`` as the :class:`State` of configuration ``id`` of ``sender``'s
    run ``epoch`` at ``step``; ``None`` if a list of it is longer than a
    State may carry (:data:`MAX_FACTS`): no robot is told a part of it."""
    lists = (
        situation.asserted,
        situation.retracted,
        situation.failed,
        situation.media_down,
        situation.reliability,
    )
    if any(len(items) > MAX_FACTS for items in lists):
        return None
    return State(
        id,
        sender,
        epoch,
        step,
        added=situation.asserted,
        removed=situation.retracted,
        failed=situation.failed,
        down=situation.media_down,
        reliability=situation.reliability,
    )


def _shown(item: Ground) -> str:
    """A fact or instance from the network, as the console may print it."""
    return printable(clip(f"({' '.join(item)})", 200))


def situation_of(state: State, task: Task) -> tuple[Situation, tuple[str, ...]]:
    """The situation ``state`` says the society committed, checked against
    ``task`` (module docstring), and what was dropped of it (one line each)."""
    dropped: list[str] = []

    def fact(items: tuple[Ground, ...], what: str) -> tuple[Ground, ...]:
        kept = []
        for item in items:
            if item[0].startswith(":"):
                dropped.append(f"{what}, {_shown(item)}: no state can write a fact of {item[0]}")
            else:
                kept.append(item)
        return tuple(kept)

    def instance(item: Ground) -> bool:
        if task.functionality(item) is None:
            dropped.append(f"{_shown(item)}: not an instance of a functionality of the domain")
            return False
        return True

    situation = Situation().updated(
        fact(state.added, "a fact added"), fact(state.removed, "a fact removed")
    )  # the way the coordinator itself takes them: each once, and none both added and removed
    for item in state.failed:
        if instance(item):
            situation = situation.failing(item)
    media = len(task.media)
    for index in state.down:
        if index < media:
            situation = situation.medium_down(index)
        else:
            dropped.append(f"medium {index}: the state declares {media} media")
    for item, p in state.reliability:
        if instance(item):
            situation = situation.with_reliability(item, p)
    return situation, tuple(dropped)
