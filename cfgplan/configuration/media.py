"""Communication admissibility (thesis 3.5, 4.6): every global channel between
two different robots is carried by a medium from its sender to its receiver,
and no medium carries more than its capacity.

A channel without a declared bandwidth still needs a medium and loads it by 0.
When several media connect the same pair, any assignment that fits will do:
:func:`assign` searches them exhaustively (channels largest first, each pair
of robots on its own, without recursion), so it finds one whenever one exists.
"""

from __future__ import annotations

import math
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
    present = [(i, d) for i, d in enumerate(demands) if d is not None]
    for _, d in present:
        if not any(m.sender == d.sender and m.receiver == d.receiver for m in media):
            return MediaResult(
                None, {}, f"no medium from {d.sender} to {d.receiver} for a global channel"
            )
    present.sort(key=lambda item: (-item[1].bandwidth, item[0]))
    loads = [0.0] * len(media)
    chosen: dict[int, int] = {}
    pairs: dict[tuple[str, str], list[tuple[int, Demand]]] = {}
    for i, d in present:
        pairs.setdefault((d.sender, d.receiver), []).append((i, d))
    # The pairs are independent: searching each alone finds the same assignment
    # as searching them all together, without multiplying their alternatives;
    # a pair that needs more than all its media carry fails without a search.
    for (sender, receiver), group in pairs.items():
        links = [j for j, m in enumerate(media) if (m.sender, m.receiver) == (sender, receiver)]
        need = math.fsum(d.bandwidth for _, d in group)
        room = math.fsum(media[j].capacity for j in links)
        if need > room or not _fits(group, links, media, loads, chosen):
            return MediaResult(None, {}, _overflow(demands, media))
    return MediaResult(dict(sorted(chosen.items())), dict(enumerate(loads)))


def _fits(
    group: Sequence[tuple[int, Demand]],
    links: Sequence[int],
    media: Sequence[Medium],
    loads: list[float],
    chosen: dict[int, int],
) -> bool:
    """Depth first: each demand of ``group`` on the first of ``links`` with room,
    backtracking to the next medium when the demands after it do not fit.
    An explicit stack (the medium chosen for each placed demand), no recursion."""
    picks: list[int] = []  # position in links of each placed demand's medium
    start = 0
    while len(picks) < len(group):
        i, d = group[len(picks)]
        for p in range(start, len(links)):
            j = links[p]
            if loads[j] + d.bandwidth <= media[j].capacity:
                loads[j] += d.bandwidth
                chosen[i] = j
                picks.append(p)
                start = 0
                break
        else:
            if not picks:
                return False
            p = picks.pop()
            i, d = group[len(picks)]
            loads[links[p]] -= d.bandwidth
            del chosen[i]
            start = p + 1
    return True


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
