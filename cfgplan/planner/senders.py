"""Where each ground method instance can send its outputs from (thesis 4.5,
step 3d): the expansions whose channels can never get their sending end onto
the robot they declare.

A channel declared ``(local ?r)`` must run from a functionality on ``?r``, one
declared ``(global ?a ?b)`` from one on ``?a`` (step 4; the search checks it
when both ends are placed, :func:`cfgplan.planner.wiring.resolve`). When the
sending end is a method instance, it is re-wired through that instance's
``:out`` to the item that produces the data (step 3d), and again until it
reaches a functionality; its robot is the functionality's first argument. So
each ground method instance has, for each data descriptor it can send, the
set of robots its producer can end up on: its *senders*. They are the least
fixpoint of

    senders(m)[d] = the union, over the expansions e of m that can be placed,
                    of {r} when e's ``:out`` entry for d is a functionality on r,
                    or senders(c)[d] when it is a method instance c,

where an expansion can be placed when every item of its body can (a
functionality under some binding of its preconditions, a method instance
when it has an expansion that can be placed) and every channel of it from a
body item has its declared sending robot among that item's senders of its
data. An instance with no such expansion has no senders and cannot be placed.

The fixpoint is the least one, computed by chaotic iteration from "nothing
can be placed" up (every change re-evaluates the callers), so that a
recursive method claims only what some finite derivation gives it. That is
sound for the search: a derivation is a finite tree, built from the bottom
up out of expansions that can be placed, and the recursion guard of 4.5 only
removes derivations.

An expansion with a channel from a method instance that can send the
channel's data, but never from the robot the channel declares, is therefore
a dead end wherever it is met, though the search would find it out only at
the end of every derivation below it (a delegation chain that ends on
another robot: :func:`benchmarks.families.any_delegation`). The grounder
gives it as one (:meth:`cfgplan.planner.ground.Grounder.expansions`), with
its reason, and neither the search nor the bounds expand it. Nothing that
can complete is lost, and the order of what is listed does not change (the
expansion keeps its number among the method's choices). Other expansions
that cannot be placed are left to the search, which says why where it meets
the cause (:meth:`Placement.misplaced`).

Only sending ends are followed: the receiving end of a channel into a method
is re-wired to every item its ``:in`` names, a condition on all of them,
left to the search. A channel declared ``any`` is checked as the local or
global channel its robots made it when the expansion was instantiated
(:func:`cfgplan.planner.ground.channel_kind`); an expansion's robots are
ground (an unbound one is a dead end of its own, :func:`~cfgplan.planner.ground.instantiate`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

from cfgplan.notation import atom_text, call_text
from cfgplan.planner import clock
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import Ground, Task

Senders = Mapping[Ground, frozenset[str]]
"""Data descriptor -> the robots its producer can be on."""

Spec = tuple[str, Ground, int, int, Ground, float | None]
"""A channel of an expansion: (kind, robots, source offset, target offset, data, bandwidth)."""


class Body(Protocol):
    """What the analysis reads of one expansion (the grounder's ``Expansion``)."""

    @property
    def channels(self) -> tuple[Spec, ...]: ...
    @property
    def body(self) -> tuple[Ground, ...]: ...
    @property
    def outputs(self) -> Mapping[Ground, tuple[int, float | None]]: ...


Value = dict[Ground, frozenset[str]] | None
"""A method instance's senders; None: it cannot be placed."""

Known = Callable[[Ground], Value]
"""The senders known of a method instance (while solving: the current guess)."""


Expansions = Callable[[Ground], Iterable[Body | DeadEnd]]
"""A method call's expansions, every version's in order (dead ends included)."""


@dataclass(eq=False, repr=False)
class Placement:
    """The senders of one task's ground method instances, computed over the
    part of the graph of ground instances below each call first asked for."""

    task: Task
    expansions: Expansions
    """Every expansion of a method call, unfiltered (the grounder's)."""
    placeable: Callable[[Ground], bool]
    """Whether a functionality call has a binding of its preconditions."""
    _senders: dict[Ground, Value] = field(default_factory=dict)
    """Method call -> its senders: the least fixpoint, final once set (a
    search stopped while solving leaves none of its guesses here)."""

    def senders(self, call: Ground) -> Senders | None:
        """The senders of method instance ``call`` (None: it cannot be placed)."""
        if call not in self._senders:
            self._solve(call)
        return self._senders[call]

    def misplaced(self, body: Body) -> DeadEnd | None:
        """Why ``body``'s expansion can never be placed, or None, given that
        what is below it is analysed (:meth:`senders` of its caller): a
        channel from a method instance that can send the channel's data, but
        never from the robot the channel declares. (Other expansions that
        cannot be placed are left to the search, which says why where it
        meets the cause: a functionality on the wrong robot as soon as both
        ends are placed, a precondition no binding satisfies, an ``:out``
        that does not produce the data.)"""
        for kind, robots, source, _, data, _ in self._checked(body):
            sender = body.body[source]
            if self.task.is_method(sender):
                # (not analysed: the expansion is ruled out by a functionality
                # of its body, left to the search to say)
                value = self._senders.get(sender)
                senders = frozenset() if value is None else value.get(data, frozenset())
                if senders and robots[0] not in senders:
                    return _unsendable(kind, robots, sender, data, senders)
        return None

    def _solve(self, root: Ground) -> None:
        """The least fixpoint over the method instances below ``root`` not yet
        analysed (those already analysed are final: what is below them was)."""
        found: dict[Ground, list[_Step]] = {}
        callers: dict[Ground, set[Ground]] = {}
        todo = [root]
        while todo:
            clock.check()
            call = todo.pop()
            if call in found:
                continue
            steps = found[call] = []
            for body in self.expansions(call):
                if isinstance(body, DeadEnd):
                    continue
                step = self._step(body)
                if step is None:
                    continue
                steps.append(step)
                for child in step.methods:
                    if child not in self._senders:
                        callers.setdefault(child, set()).add(call)
                        if child not in found:
                            todo.append(child)
        values: dict[Ground, Value] = dict.fromkeys(found)

        def known(call: Ground) -> Value:
            return values[call] if call in values else self._senders[call]

        queue = list(found)
        waiting = set(queue)
        while queue:
            clock.check()
            call = queue.pop()
            waiting.discard(call)
            value = _value(found[call], known)
            if value != values[call]:
                values[call] = value
                for caller in callers.get(call, ()):
                    if caller not in waiting:
                        waiting.add(caller)
                        queue.append(caller)
        self._senders.update(values)

    def _step(self, body: Body) -> _Step | None:
        """What the fixpoint reads of an expansion, worked out once; None when
        it can never be placed whatever the methods below it send (a
        functionality of its body without a binding, or on another robot
        than a channel from it declares)."""
        task = self.task
        methods: list[Ground] = []
        for child in body.body:
            if task.is_method(child):
                methods.append(child)
            elif task.functionality(child) is not None and not self.placeable(child):
                return None
        checks: list[tuple[str, Ground, Ground]] = []
        for _, robots, source, _, data, _ in self._checked(body):
            sender = body.body[source]
            if task.is_method(sender):
                checks.append((robots[0], sender, data))
            elif len(sender) < 2 or sender[1] != robots[0]:
                return None
        outputs: list[tuple[Ground, Ground | None, frozenset[str]]] = []
        for data, (offset, _) in body.outputs.items():
            producer = body.body[offset]
            if task.is_method(producer):
                outputs.append((data, producer, frozenset()))
            elif len(producer) > 1:
                outputs.append((data, None, frozenset({producer[1]})))
        return _Step(tuple(dict.fromkeys(methods)), tuple(checks), tuple(outputs))

    @staticmethod
    def _checked(body: Body) -> Iterator[Spec]:
        """The channels whose sending robot is checked: local and global ones
        (an ``any`` channel is one of them once instantiated)."""
        for spec in body.channels:
            if spec[0] in ("local", "global") and spec[1]:
                yield spec


class _Step(NamedTuple):
    """An expansion as the fixpoint reads it (:meth:`Placement._step`)."""

    methods: tuple[Ground, ...]
    """The method instances of its body: each must be placeable."""
    checks: tuple[tuple[str, Ground, Ground], ...]
    """(robot, method instance, data): a channel from it must start on robot."""
    outputs: tuple[tuple[Ground, Ground | None, frozenset[str]], ...]
    """(data, the method instance producing it, or None and the robot of the
    functionality that does)."""


def _value(steps: list[_Step], known: Known) -> Value:
    """A method instance's senders from its expansions, given ``known``."""
    value: dict[Ground, set[str]] | None = None
    for step in steps:
        if not all(known(m) is not None for m in step.methods):
            continue
        if not all(robot in _sent(known, m, d) for robot, m, d in step.checks):
            continue
        if value is None:
            value = {}
        for data, producer, robots in step.outputs:
            sent = robots if producer is None else _sent(known, producer, data)
            if sent:
                value.setdefault(data, set()).update(sent)
    return None if value is None else {d: frozenset(r) for d, r in value.items()}


def _sent(known: Known, call: Ground, data: Ground) -> frozenset[str]:
    """The robots method instance ``call`` can send ``data`` from, given ``known``."""
    senders = known(call)
    return frozenset() if senders is None else senders.get(data, frozenset())


def _unsendable(
    kind: str, robots: Ground, sender: Ground, data: Ground, senders: frozenset[str]
) -> DeadEnd:
    where = ", ".join(sorted(senders)) if senders else "no robot"
    return DeadEnd(
        f"{kind} channel {atom_text(data)}",
        f"declared ({kind} {' '.join(robots)}) but {call_text(sender)} can send "
        f"{atom_text(data)} only from {where}",
        condition=Condition.LOCATION,
    )
