"""What an instance can reach through method bodies, by its signature: the
functionality names and the data predicates of the channels its
derivations can contain. The first bound names the parts that may share by
them (:mod:`cfgplan.planner.summary`, :mod:`cfgplan.planner.bound`,
:func:`cfgplan.planner.parts.least`): parts that reach no common name
cannot share an instance or merge a channel.

A signature reaches what the signatures its methods' bodies call reach
(every version, every binding: a superset, which only weakens the bound);
where no signature reaches itself this is made children first, each from
its children's, else by a walk of its own.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cfgplan.planner.task import Ground, Signature, Task

Reached = tuple[frozenset[str], frozenset[str], frozenset[str]]
"""The functionality names, the channels' data predicates, and the two together."""


@dataclass(eq=False, repr=False)
class Reach:
    """What each signature of one task can reach, memoised."""

    task: Task
    _reached: dict[Signature, Reached] = field(default_factory=dict)
    _by_call: dict[Ground, Reached] = field(default_factory=dict)

    def names(self, call: Ground) -> frozenset[str]:
        """The functionality names an instance can reach through method bodies."""
        return self.of(call)[0]

    def of(self, call: Ground) -> Reached:
        """:meth:`names`; the data predicates of the channels its expansions
        can create; and the two together."""
        found = self._by_call.get(call)
        if found is None:
            found = self._by_call[call] = self._signature((call[0], len(call) - 1))
        return found

    def _signature(self, sig: Signature) -> Reached:
        found = self._reached.get(sig)
        if found is not None:
            return found
        if not self.task.recursive:
            return self._below(sig)
        names: set[str] = set()
        data: set[str] = set()
        seen = {sig}
        todo = [sig]
        while todo:
            current = todo.pop()
            if current in self.task.functionalities:
                names.add(current[0])
                continue
            for method in self.task.methods.get(current, ()):
                data.update(c.data[0] for c in method.channels)
                for _, pattern in method.body:
                    child = (pattern[0], len(pattern) - 1)
                    if child not in seen:
                        seen.add(child)
                        todo.append(child)
        result = self._reached[sig] = (frozenset(names), frozenset(data), frozenset(names | data))
        return result

    def _below(self, sig: Signature) -> Reached:
        """:meth:`_signature` where no signature reaches itself: each
        from the signatures its bodies call, children first (no walk below
        every level of a deep hierarchy again)."""
        task, reached = self.task, self._reached
        stack: list[tuple[Signature, bool]] = [(sig, False)]
        while stack:
            current, ready = stack.pop()
            if current in reached:
                continue
            if current in task.functionalities:
                reached[current] = (frozenset({current[0]}), frozenset(), frozenset({current[0]}))
                continue
            versions = task.methods.get(current, ())
            # Each signature once: on a chain every version calls the level
            # below, whose sets (every name below it) are then joined once.
            children = list(dict.fromkeys((p[0], len(p) - 1) for m in versions for _, p in m.body))
            if not ready:
                stack.append((current, True))
                stack.extend((child, False) for child in children if child not in reached)
                continue
            names: list[frozenset[str]] = []
            data = [frozenset(c.data[0] for m in versions for c in m.channels)]
            for child in children:
                below = reached.get(child)
                if below is not None:  # None: a name neither method nor functionality
                    names.append(below[0])
                    data.append(below[1])
            # Each set made once (no set copied into a frozenset).
            reached_names, reached_data = frozenset().union(*names), frozenset().union(*data)
            reached[current] = (reached_names, reached_data, reached_names | reached_data)
        return reached[sig]
