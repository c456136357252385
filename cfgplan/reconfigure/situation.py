"""What has changed since the state was read, and the task to re-plan with (5.5, 7.2).

A :class:`Situation` records what the run has learned: functionality
instances that failed, robots lost, media down, facts the operator (or an
action's postconditions, 4.5) added or removed, and reliabilities lowered by
failures. :func:`derive` turns the task compiled once from the domain and
the state into the task of that situation *without reading, checking or
compiling the domain again* (no cold start): the same schemas, the facts
changed and re-indexed, and — when something failed — guards on the
functionality operators concerned:

* ``(not (:out-of-service NAME ARGS...))`` on the operators of failed
  instances: a failed instance is never placed again, whatever facts remain
  (a computation that fails withdraws no fact,
  :mod:`~cfgplan.reconfigure.withdraw`);
* ``(not (:lost ROBOT))`` on every operator's first argument, when a robot
  is lost: nothing runs on it.

The guard facts go into the derived state only; their predicates start with
``:``, which no domain or state can write, so they never meet a user's fact. When no
configuration is admissible, the planner's explanation names them
(``a fact matches the negated (:out-of-service compass Emil)``) or the facts
withdrawn (``no fact matches (compass Emil)``).

A situation is immutable and hashable, so derived tasks (and the planner's
caches, which are kept per task) are reused when a situation comes back.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass
from types import MappingProxyType

from cfgplan.configuration.model import Configuration
from cfgplan.planner.task import FunctionalitySchema, Ground, Task, Test, TestKind
from cfgplan.planner.task import derive as derive_task
from cfgplan.reconfigure.withdraw import withdrawn_by_failure, withdrawn_by_loss

__all__ = ["LOST", "OUT_OF_SERVICE", "Situation", "derive"]

OUT_OF_SERVICE = ":out-of-service"
"""Predicate of the guard fact of a failed instance (a name starting with
``:`` is a keyword to the reader, so no domain or state can write it)."""

LOST = ":lost"
"""Predicate of the guard fact of a lost robot."""


def _add(items: tuple[Ground, ...], item: Ground) -> tuple[Ground, ...]:
    return items if item in items else (*items, item)


def _drop(items: tuple[Ground, ...], item: Ground) -> tuple[Ground, ...]:
    return tuple(x for x in items if x != item)


@dataclass(frozen=True)
class Situation:
    """What the run has learned, on top of the state read at the start."""

    failed: tuple[Ground, ...] = ()
    """Functionality instances out of service, e.g. ``("compass", "Emil")``."""
    lost: tuple[str, ...] = ()
    """Robots (agents) gone."""
    media_down: tuple[int, ...] = ()
    """Indexes into the state's media of media that failed."""
    asserted: tuple[Ground, ...] = ()
    """Facts added (operator, postconditions)."""
    retracted: tuple[Ground, ...] = ()
    """Facts removed (operator, postconditions)."""
    reliability: tuple[tuple[Ground, float], ...] = ()
    """Functionality instances whose reliability (7.2) was lowered."""

    def __bool__(self) -> bool:
        return any(dataclasses.astuple(self))

    def failing(self, instance: Ground) -> Situation:
        return dataclasses.replace(self, failed=_add(self.failed, instance))

    def recovered(self, instance: Ground) -> Situation:
        return dataclasses.replace(self, failed=_drop(self.failed, instance))

    def losing(self, robot: str) -> Situation:
        lost = self.lost if robot in self.lost else (*self.lost, robot)
        return dataclasses.replace(self, lost=lost)

    def returning(self, robot: str) -> Situation:
        return dataclasses.replace(self, lost=tuple(r for r in self.lost if r != robot))

    def medium_down(self, index: int) -> Situation:
        down = self.media_down if index in self.media_down else (*self.media_down, index)
        return dataclasses.replace(self, media_down=down)

    def medium_up(self, index: int) -> Situation:
        return dataclasses.replace(self, media_down=tuple(i for i in self.media_down if i != index))

    def updated(self, add: Iterable[Ground] = (), remove: Iterable[Ground] = ()) -> Situation:
        """An operator's state update (or postconditions): facts added and removed."""
        asserted, retracted = self.asserted, self.retracted
        for fact in remove:
            asserted, retracted = _drop(asserted, fact), _add(retracted, fact)
        for fact in add:
            retracted, asserted = _drop(retracted, fact), _add(asserted, fact)
        return dataclasses.replace(self, asserted=asserted, retracted=retracted)

    def with_reliability(self, instance: Ground, p: float) -> Situation:
        kept = tuple((k, v) for k, v in self.reliability if k != instance)
        return dataclasses.replace(self, reliability=(*kept, (instance, p)))

    def breaks(self, config: Configuration) -> bool:
        """Whether ``config`` relies on something out of service here: a failed
        functionality instance, a lost robot, a medium down (a configuration
        rolled back to after an aborted switch may)."""
        return (
            any(f.key in self.failed for f in config.functionalities)
            or any(agent in self.lost for agent in config.agents)
            or any(a.medium in self.media_down for a in config.media)
        )

    def withdrawn(self, base: Task) -> tuple[Ground, ...]:
        """The facts of ``base``'s state that the failures and losses withdraw."""
        out: dict[Ground, None] = {}
        for instance in self.failed:
            out.update(dict.fromkeys(withdrawn_by_failure(base, instance)))
        for robot in self.lost:
            out.update(dict.fromkeys(withdrawn_by_loss(base, robot)))
        return tuple(out)

    def facts(self, base: Task) -> tuple[Ground, ...]:
        """The facts of the situation, in state order, the added ones last."""
        gone = set(self.withdrawn(base)) | set(self.retracted)
        kept = [f for f in base.facts if f not in gone]
        return tuple(dict.fromkeys([*kept, *self.asserted]))


def _guarded(schema: FunctionalitySchema, failed: bool, lost: bool) -> FunctionalitySchema:
    """``schema`` with the guards it needs: out of service when an instance of
    it failed, lost when a robot was (the others are not slowed down)."""
    if not schema.params or not (failed or lost):
        return schema
    tests = list(schema.tests)
    if failed:
        tests.append(Test(TestKind.NOT, (OUT_OF_SERVICE, schema.name, *schema.params)))
    if lost:
        tests.append(Test(TestKind.NOT, (LOST, schema.params[0])))
    return schema._replace(tests=tuple(tests))


def derive(base: Task, situation: Situation) -> Task:
    """The task of ``situation``: ``base`` with its facts, media, guards and
    reliabilities changed (module docstring); ``base`` itself when nothing changed."""
    if not situation:
        return base
    facts = situation.facts(base)
    functionalities = base.functionalities
    if situation.failed or situation.lost:
        guards = [(OUT_OF_SERVICE, *f) for f in situation.failed]
        guards += [(LOST, r) for r in situation.lost]
        facts = (*facts, *guards)
        failed_names = {f[0] for f in situation.failed}
        functionalities = MappingProxyType(
            {
                signature: _guarded(schema, schema.name in failed_names, bool(situation.lost))
                for signature, schema in base.functionalities.items()
            }
        )
    media = tuple(m for i, m in enumerate(base.media) if i not in situation.media_down)
    reliability = dict(base.reliability)
    reliability.update(situation.reliability)
    changed = functionalities if functionalities is not base.functionalities else None
    return derive_task(base, facts, functionalities=changed, media=media, reliability=reliability)
