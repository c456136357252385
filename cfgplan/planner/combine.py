"""Configurations of independent parts, listed cheapest first.

When the choices of a goal fall into independent parts
(:mod:`cfgplan.planner.components`), each part is searched on its own, best
first (:class:`cfgplan.planner.search.BestFirst` from the part's start,
listing the complete nodes step 4 admits: only their choices are combined,
so no part's configuration is built), and the configurations of the goal
are the combinations of one configuration per part: the cost of the forced
steps plus what each part adds. They are listed as the k cheapest sums are
(:func:`cfgplan.planner.ranking.merge`: taking a combination offers each
part's next configuration in its place), each part's list grown only as far
as the merge needs it.

At equal cost the thesis lists derivations in their depth-first order: the
first choice item (by address) where two combinations differ decides, by
the choices made below it. So a combination's place is its cost, then the
choices below every choice item in address order; a part's own search lists
its configurations in that same order, so a successor never comes before the
combination it was offered by, and the merge lists in the thesis's order
(:mod:`cfgplan.planner.ranking`).

Each combination listed is derived again from the goal in the thesis's
order (:func:`cfgplan.planner.components.replay`, resumed from the last
derivation at the first choice the two make differently): labels, channel
order and cost are exactly the plain search's, and the check of 4.5 step 4 rejects
a combination with a cycle through the forced functionalities. Should a
derivation break off, or cost other than its parts' sum, or a part meet a
derivation it listed already (the plain search would number the
configurations after it differently), the plain search takes over and lists
what remains after those already listed.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.components import Address, Parts, Trail, replay, segments
from cfgplan.planner.grow import Completion, Grower
from cfgplan.planner.partial import Partial
from cfgplan.planner.pricer import Pricer
from cfgplan.planner.ranking import merge
from cfgplan.planner.report import Report, Stats, Status
from cfgplan.planner.search import BestFirst, Progress
from cfgplan.planner.task import Ground


class _Entry(NamedTuple):
    """One configuration of a part: what it adds to the forced steps' cost,
    and the choices below each of the part's items."""

    added: float
    choices: dict[Address, tuple[int, ...]]


_Offer = tuple[float, tuple[tuple[int, ...], ...], tuple[int, ...]]
"""A combination's place — cost, then the choices below each choice item in
address order — and which configuration of each part it takes."""


class _Irregular(Exception):
    """The parts turned out not to combine as assumed: hand over."""


@dataclass(eq=False, repr=False)
class Combined:
    """An iterator over configurations, best first, part by part."""

    plain: Grower
    """The plain search's grower: what the parts hand over to, if they must."""
    plain_pricer: Pricer
    """The plain search's pricer, as :attr:`plain`."""
    goal: Ground
    parts: Parts
    make: Callable[[frozenset[int]], tuple[Grower, Pricer]]
    """A fresh grower and pricer for each part's search, given the labels of
    the functionalities the forced steps placed (:attr:`Grower.given`)."""
    progress: Progress | None = None
    status: Status = Status.COMPLETE
    stats: Stats = field(default_factory=Stats)
    handed_over: bool = False
    """Whether the plain search lists the rest (the parts did not combine)."""
    _searches: list[BestFirst] = field(default_factory=list)
    _streams: list[Iterator[Completion]] = field(default_factory=list)
    _starts: list[tuple[Partial, dict[int, Address]]] = field(default_factory=list)
    """Each part's start node and its choice items' addresses by label."""
    _lists: list[list[_Entry]] = field(default_factory=list)
    """Each part's configurations found so far, in its search's order."""
    _start: float = 0.0
    _trail: Trail = field(default_factory=Trail)
    """The last replay's choices, for the next to resume from."""

    def __post_init__(self) -> None:
        # Every choice item's address, and its part, in the thesis's order.
        parts = self.parts
        self._order = sorted(
            (parts.address[item.label], p) for p, items in enumerate(parts.parts) for item in items
        )
        self._own = self.make(self.plain.given)
        """The combinations' grower and pricer: step 4 for each combination
        (:meth:`_derived`), the greedy dive. Not the plain search's: that one,
        handed over to, derives everything again from the goal, and would
        count what the combinations rejected a second time."""

    @property
    def grower(self) -> Grower:
        """The grower of the search under way, which its report and counts
        are in and a greedy dive goes on with: the combinations' own, or,
        once handed over, the plain search's."""
        return self.plain if self.handed_over else self._own[0]

    @property
    def pricer(self) -> Pricer:
        """The pricer of the search under way, as :attr:`grower`."""
        return self.plain_pricer if self.handed_over else self._own[1]

    @property
    def report(self) -> Report:
        """What the search under way met (:attr:`grower`'s): the combinations'
        rejections and the dive's dead ends, or the plain search's."""
        return self.grower.report

    def __iter__(self) -> Iterator[Configuration]:
        start = self._start = time.perf_counter()
        listed = 0
        try:
            try:
                for config in self._combine():
                    listed += 1
                    self.stats.seconds = time.perf_counter() - start  # the caller may stop here
                    yield config
            except _Irregular:
                for config in self._hand_over(listed):
                    self.stats.seconds = time.perf_counter() - start
                    yield config
        except clock.OutOfTime:
            self.status = Status.TIME_LIMIT
        self.stats.seconds = time.perf_counter() - start

    def _combine(self) -> Iterator[Configuration]:
        parts = self.parts
        for p in range(len(parts.parts)):
            grower, pricer = self.make(frozenset(parts.node.located))
            self._starts.append((parts.start(p), parts.owners(p)))
            search = BestFirst(grower, pricer, self.goal, self._progress, origin=self._starts[p][0])
            self._searches.append(search)
            self._streams.append(search.completions())
            self._lists.append([])
        first = self._offer((0,) * len(parts.parts))
        if first is None:  # some part has no configuration: let the plain search say why
            raise _Irregular
        offered = {first[2]}

        def offers(offer: _Offer) -> Iterator[_Offer]:
            """Each part's next configuration in place of the one ``offer``
            takes: no earlier in the listing (a part lists in that order)."""
            at = offer[2]
            for p in range(len(at)):
                then = (*at[:p], at[p] + 1, *at[p + 1 :])
                if then not in offered:
                    offered.add(then)
                    made = self._offer(then)
                    if made is not None:
                        yield made

        for total, _, at in merge([first], offers, lambda _: True):
            config = self._derived(at, total)
            if config is not None:
                yield config

    def _derived(self, at: tuple[int, ...], total: float) -> Configuration | None:
        """The combination ``at`` derived again from the goal in the thesis's
        order: its configuration, or None when step 4 rejects it (a cycle
        through the forced functionalities)."""
        choices: dict[Address, tuple[int, ...]] = {}
        for p, i in enumerate(at):
            choices.update(self._lists[p][i].choices)
        node = replay(self.grower.grounder, self.goal, choices, self._trail)
        if node is None or self.pricer.cost(node) != total:
            raise _Irregular
        config = self.grower.finish(node, total, self.stats.derivations + 1)
        if config is None:
            self.stats.rejected += 1
            return None
        self.stats.derivations += 1
        return config

    def _offer(self, at: tuple[int, ...]) -> _Offer | None:
        """The combination of the ``at[p]``-th configuration of each part p,
        with its place in the listing; None when a part has no more."""
        chosen = []
        raw = self.parts.node.cost
        for p, i in enumerate(at):
            got = self._entry(p, i)
            if got is None:
                return None
            chosen.append(got)
            raw += got.added
        key = tuple(chosen[p].choices[a] for a, p in self._order)
        return self.grower.levels.cost(raw), key, at

    def _entry(self, p: int, i: int) -> _Entry | None:
        """Part p's ``i``-th configuration (a completion of its search, searched
        as far as needed, not built), or None."""
        found = self._lists[p]
        while len(found) <= i:
            search = self._searches[p]
            admitted = next(self._streams[p], None)
            self._count()
            if search.status.stopped:
                self.status = search.status
                raise clock.OutOfTime
            if search.stats.duplicates:
                raise _Irregular
            if admitted is None:
                return None
            start, owners = self._starts[p]
            made = segments(self.grower.grounder, start, admitted.node.path, owners)
            if made is None:
                raise _Irregular
            found.append(_Entry(admitted.node.cost - start.cost, made))
        return found[i]

    def _progress(self, stats: Stats, elapsed: float) -> None:
        """A part's search reports progress: report this search's."""
        if self.progress is not None:
            self._count()
            self.progress(self.stats, time.perf_counter() - self._start)

    def _count(self) -> None:
        """The parts' statistics, summed into this search's."""
        for name in ("nodes", "expansions", "pruned"):
            setattr(self.stats, name, sum(getattr(s.stats, name) for s in self._searches))

    def _hand_over(self, listed: int) -> Iterator[Configuration]:
        """The plain search, skipping the ``listed`` configurations already listed."""
        plain = BestFirst(self.plain, self.plain_pricer, self.goal, self.progress)
        self.stats, self.handed_over = plain.stats, True
        for config in plain:
            if listed:
                listed -= 1
            else:
                yield config
        self.status = plain.status
