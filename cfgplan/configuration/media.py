"""Communication admissibility (thesis 3.5, 4.6): every global channel between
two different robots is carried by a medium from its sender to its receiver,
and no medium carries more than its capacity.

A channel without a declared bandwidth still needs a medium and loads it by 0.
When several media connect the same pair, any assignment that fits will do:
:func:`assign` searches them exhaustively (channels largest first), so it
finds one whenever one exists.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from cfgplan.configuration.cost import fmt
from cfgplan.ir.model import Medium


@dataclass(frozen=True)
class Demand:
    """A global channel's need: from, to, bandwidth (0 when undeclared)."""

    sender: str
    receiver: str
    bandwidth: float


@dataclass(frozen=True)
class MediaResult:
    """An assignment (channel index -> medium index), or why none exists."""

    assignment: dict[int, int] | None
    loads: dict[int, float]
    problem: str = ""

    @property
    def ok(self) -> bool:
        return self.assignment is not None


def describe(medium: Medium) -> str:
    return (
        f"medium {medium.type} {medium.sender}->{medium.receiver} (capacity {fmt(medium.capacity)})"
    )


def assign(demands: Sequence[Demand | None], media: Sequence[Medium]) -> MediaResult:
    """Assign each demand (None: no medium needed) to a medium that fits."""
    todo = [i for i, d in enumerate(demands) if d is not None]
    for i in todo:
        d = demands[i]
        assert d is not None
        if not any(m.sender == d.sender and m.receiver == d.receiver for m in media):
            return MediaResult(
                None, {}, f"no medium from {d.sender} to {d.receiver} for a global channel"
            )
    todo.sort(key=lambda i: (-(demands[i].bandwidth), i))  # type: ignore[union-attr]
    loads = [0.0] * len(media)
    chosen: dict[int, int] = {}

    def fits(k: int) -> bool:
        if k == len(todo):
            return True
        i = todo[k]
        d = demands[i]
        assert d is not None
        for j, m in enumerate(media):
            same_pair = m.sender == d.sender and m.receiver == d.receiver
            if same_pair and loads[j] + d.bandwidth <= m.capacity:
                loads[j] += d.bandwidth
                chosen[i] = j
                if fits(k + 1):
                    return True
                loads[j] -= d.bandwidth
                del chosen[i]
        return False

    if fits(0):
        return MediaResult(dict(sorted(chosen.items())), dict(enumerate(loads)))
    return MediaResult(None, {}, _overflow(demands, media))


def _overflow(demands: Sequence[Demand | None], media: Sequence[Medium]) -> str:
    """Name the pair whose channels cannot fit, and by how much."""
    pairs: dict[tuple[str, str], float] = {}
    for d in demands:
        if d is not None:
            pairs[(d.sender, d.receiver)] = pairs.get((d.sender, d.receiver), 0.0) + d.bandwidth
    for (sender, receiver), need in pairs.items():
        links = [m for m in media if m.sender == sender and m.receiver == receiver]
        capacity = sum(m.capacity for m in links)
        if (need > capacity or len(links) == 1) and need > capacity:
            names = ", ".join(describe(m) for m in links)
            return (
                f"{names} overflows: the global channels from {sender} to {receiver} "
                f"need {fmt(need)}, {fmt(need - capacity)} more than it carries"
            )
    return "the global channels cannot be split over the media without overflowing one"
