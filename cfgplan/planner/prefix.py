"""The first ``-k N`` results of a search, and whether one more exists.

``cfgplan plan -k N`` says whether more configurations (or sequences) exist
than it lists. Searching for the (N+1)-th without a bound would, where
fewer exist, run the search to its end: ``-k 1`` would cost what ``--all``
does. So, once N are listed, the search goes on for one more with at most as
much work again as the first N took (at least :attr:`Prefix.least` steps of
:func:`cfgplan.planner.clock.check`, the same count on every machine): one
found, the status (:class:`cfgplan.planner.report.Status`) is ``MORE``; the
search ended, ``COMPLETE``; the work ran out, ``UNKNOWN``. One rule, used by
:class:`cfgplan.planner.plan.Run` and :class:`cfgplan.planner.sequence.SequenceSearch`.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Generic, TypeVar

from cfgplan.planner import clock
from cfgplan.planner.report import Status

T = TypeVar("T")


@dataclass(eq=False, repr=False)
class Prefix(Generic[T]):
    """Take the first :attr:`limit` of a search (None: all), looking ahead for one more."""

    limit: int | None
    ahead: bool = False
    """Once :attr:`limit` are listed, look for one more (not listed)."""
    least: int = 10_000
    """The least work the look-ahead may do, whatever the first ones took."""
    status: Status = field(init=False, default=Status.COMPLETE)
    """COMPLETE, the search ended; with :attr:`ahead`, MORE, one more exists,
    or UNKNOWN, the look-ahead's work ran out; without, CUT once :attr:`limit`
    are listed."""

    def take(self, found: Iterable[T]) -> Iterator[T]:
        """The first :attr:`limit` of ``found``; the work of making them (the
        first step of ``found`` included) is counted, and bounds the look-ahead."""
        listed = 0
        try:
            with clock.counting() as work:
                for item in found:
                    if self.limit is not None and listed >= self.limit:  # the look-ahead's
                        self.status = Status.MORE
                        return
                    listed += 1
                    yield item
                    if self.limit is not None and listed >= self.limit:
                        if not self.ahead:
                            self.status = Status.CUT
                            return
                        work.most = work.done + max(self.least, work.done)
        except clock.OutOfWork:
            self.status = Status.UNKNOWN
