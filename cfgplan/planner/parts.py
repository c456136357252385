"""Parts that may share: the least a set of pending items (or of one
expansion's body items) can cost together, when each is known only by the
names it can reach (:mod:`cfgplan.planner.reach`) and its own least cost
(:mod:`cfgplan.planner.summary`, :mod:`cfgplan.planner.bound`)."""

from __future__ import annotations

from collections.abc import Hashable, Set

Part = tuple[Set[Hashable], float]
"""A part of :func:`least`: the names it can reach, its least cost."""


def own_part(thing: Hashable) -> frozenset[Hashable]:
    """The names of a part that shares with no other in :func:`least`: a name
    no functionality or data predicate has (those are strings)."""
    return frozenset({("own", thing)})


WIDE = 64
"""A part reaching more names than this is *wide* (a method deep in a
hierarchy reaches every name below it): :func:`least` does not file its names
one by one, but meets it with the others as sets; the first :data:`MOST_WIDE`
such parts only, as every part is met with each of them."""

MOST_WIDE = 8

GROUPS = 16
"""While the parts met so far make at most this many groups, the next part is
met with each group (:func:`_grouped`: a few set intersections, done in C);
past it, as on a deep recursive path with hundreds of parts of their own,
the groups are found again by filing every name (:func:`_many`). On the
dag family, whose parts mostly join one group, meeting the groups takes a
third of the time filing the names does (dag D=30's estimates);
on fusion, whose groups stay apart, filing is the cheaper."""


def least(parts: list[Part]) -> float:
    """The least a set of parts can cost together, each part given by the
    names it can reach (functionality names, or channel data predicates) and
    its own least cost: parts whose names are disjoint cannot share an
    instance, so their costs add; parts that may share count as the largest
    of them. The groups' costs are added up in order of size, so that how
    the groups were found (:func:`_grouped` or :func:`_many`) makes no
    difference, float for float."""
    found = _grouped(parts, GROUPS)
    return _many(parts) if found is None else found


def _grouped(parts: list[Part], most: int) -> float | None:
    """:func:`least`, each part met with the groups found so far (groups
    have disjoint names: a part joins every group it shares a name with);
    None once more than ``most`` groups are apart."""
    alone = 0.0  # parts that reach no name: they share with nothing
    groups: list[tuple[Set[Hashable], float]] = []  # names, the dearest part's cost
    for names, part_cost in parts:
        if not names:
            alone += part_cost
            continue
        kept: list[tuple[Set[Hashable], float]] | None = None  # (most often: all join)
        for group in groups:
            if group[0].isdisjoint(names):
                if kept is None:
                    kept = []
                kept.append(group)
            else:
                names = names | group[0]
                if group[1] > part_cost:
                    part_cost = group[1]
        if kept is None:
            groups = [(names, part_cost)]
        else:
            kept.append((names, part_cost))
            groups = kept
            if len(groups) > most:
                return None
    if len(groups) == 1:
        return alone + groups[0][1]
    return alone + sum(sorted([cost for _, cost in groups]))


def _many(parts: list[Part]) -> float:
    """:func:`least` by a union-find over the parts (a deep recursive path
    has hundreds of parts of their own, each a group). A narrow part's names are filed
    (name -> a part reaching it); a wide one is met with the filed names and
    with the other wide parts by set intersections, so that the work grows
    with the narrow names, not the wide ones (a chain of D levels: D names a
    level, D levels)."""
    owner: dict[Hashable, int] = {}  # a narrow part's name -> a part that reaches it
    wide: list[tuple[int, Set[Hashable]]] = []
    parent: list[int] = []
    cost: list[float] = []

    def root(part: int) -> int:
        while parent[part] != part:
            parent[part] = parent[parent[part]]
            part = parent[part]
        return part

    def join(a: int, b: int) -> None:
        a, b = root(a), root(b)
        if a != b:
            parent[b] = a
            cost[a] = max(cost[a], cost[b])

    alone = 0.0  # parts that reach no name: they share with nothing
    for names, part_cost in parts:
        if not names:
            alone += part_cost
            continue
        part = len(parent)
        parent.append(part)
        cost.append(part_cost)
        for other, reached in wide:
            if not reached.isdisjoint(names):
                join(other, part)
        if len(names) > WIDE and len(wide) < MOST_WIDE:
            for name in owner.keys() & names:
                join(owner[name], part)
            wide.append((part, names))
            continue
        # The hot loop: join() and root() written out, this part's root kept
        # as it changes (not found again for every name it reaches).
        mine = root(part)
        for name in names:
            a = owner.setdefault(name, part)
            if a == part:
                continue
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            if a != mine:
                parent[mine] = a
                cost[a] = max(cost[a], cost[mine])
                mine = a
    # Which part ends up a group's root depends on the order names are met
    # in (a set's, which differs from one process to the next): summed in
    # order of size, the groups' costs give one float whatever it was.
    return alone + sum(sorted(c for i, c in enumerate(cost) if parent[i] == i))
