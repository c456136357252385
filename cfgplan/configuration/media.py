"""Communication admissibility (thesis 3.5, 4.6): every global channel between
two different robots is carried by a medium from its sender to its receiver,
and no medium carries more than its capacity.

A channel without a declared bandwidth still needs a medium and loads it by 0.
Media of different (sender, receiver) pairs never compete, so each pair is a
small bin-packing problem of its own: channels (items, their bandwidths) into
media (bins, their capacities). :func:`assign` settles most at once — the
channels do not fit in all the media together; one medium takes them all;
first-fit, largest channel first, works — and otherwise searches exactly,
largest channel first, never trying two media with the same room left for
one channel and never a state (channels placed, multiset of room left)
known to fail: a search over load states, not over orders, so it finds an
assignment whenever one exists without factorial work.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

from cfgplan.configuration.cost import fmt
from cfgplan.ir.model import Medium


class Demand(NamedTuple):
    """A global channel's need: from, to, bandwidth (0 when undeclared)."""

    sender: str
    receiver: str
    bandwidth: float


class MediaResult(NamedTuple):
    """An assignment (channel index -> medium index), or why none exists."""

    assignment: dict[int, int] | None
    problem: str = ""

    @property
    def ok(self) -> bool:
        return self.assignment is not None


def describe(medium: Medium) -> str:
    return (
        f"medium {medium.type} {medium.sender}->{medium.receiver} (capacity {fmt(medium.capacity)})"
    )


def _nothing() -> None:
    return None


def assign(
    demands: Sequence[Demand | None],
    media: Sequence[Medium],
    check: Callable[[], None] = _nothing,
) -> MediaResult:
    """Assign each demand (None: no medium needed) to a medium that fits.
    ``check`` is called now and then in a long search (it may raise to stop it)."""
    pairs: dict[tuple[str, str], list[int]] = {}
    for i, d in enumerate(demands):
        if d is not None:
            pairs.setdefault((d.sender, d.receiver), []).append(i)
    links_of: dict[tuple[str, str], list[int]] = {}
    for j, m in enumerate(media):
        links_of.setdefault((m.sender, m.receiver), []).append(j)
    chosen: dict[int, int] = {}
    for (sender, receiver), channels in pairs.items():
        links = links_of.get((sender, receiver))
        if not links:
            return MediaResult(None, f"no medium from {sender} to {receiver} for a global channel")
        sizes = {i: demands[i].bandwidth for i in channels}  # type: ignore[union-attr]
        packed = _pack(sizes, {j: media[j].capacity for j in links}, check)
        if packed is None:
            return MediaResult(None, _overflow(sender, receiver, sum(sizes.values()), media))
        chosen.update(packed)
    return MediaResult(dict(sorted(chosen.items())))


def _pack(
    sizes: dict[int, float], capacity: dict[int, float], check: Callable[[], None]
) -> dict[int, int] | None:
    """Channels (index -> bandwidth) into media (index -> capacity), or None."""
    order = sorted(sizes, key=lambda i: (-sizes[i], i))  # largest first
    bins = sorted(capacity)  # media in state order
    if sum(sizes.values()) > sum(capacity.values()) or sizes[order[0]] > max(capacity.values()):
        return None
    room = dict(capacity)
    first_fit: dict[int, int] = {}
    for i in order:
        j = next((j for j in bins if sizes[i] <= room[j]), None)
        if j is None:
            break
        room[j] -= sizes[i]
        first_fit[i] = j
    else:
        return first_fit
    return _search(order, sizes, bins, capacity, check)


def _search(
    order: list[int],
    sizes: dict[int, float],
    bins: list[int],
    capacity: dict[int, float],
    check: Callable[[], None],
) -> dict[int, int] | None:
    """Exact search, depth first over ``order`` (largest channel first),
    without recursion: ``cursor[d]`` is the position in ``bins`` of the medium
    tried last for the channel at depth d."""
    room = dict(capacity)
    failed: set[tuple[int, tuple[float, ...]]] = set()
    placed: list[int] = []  # the medium of each channel placed so far, by depth
    cursor: list[int] = [-1]
    while cursor:
        check()
        depth = len(placed)
        if depth == len(order):
            return {order[k]: j for k, j in enumerate(placed)}
        size = sizes[order[depth]]
        state = (depth, tuple(sorted(room.values())))
        last = cursor[-1]
        if last < 0 and state in failed:
            _back(cursor, placed, room, sizes, order)
            continue
        # Media with the same room left are the same choice for this channel.
        tried = {room[bins[b]] for b in range(last + 1)}
        following = (b for b in range(last + 1, len(bins)) if room[bins[b]] not in tried)
        nxt = next((b for b in following if size <= room[bins[b]]), None)
        if nxt is None:
            failed.add(state)
            _back(cursor, placed, room, sizes, order)
            continue
        cursor[-1] = nxt
        room[bins[nxt]] -= size
        placed.append(bins[nxt])
        cursor.append(-1)
    return None


def _back(
    cursor: list[int],
    placed: list[int],
    room: dict[int, float],
    sizes: dict[int, float],
    order: list[int],
) -> None:
    """No medium is left for the channel at this depth: leave the depth and
    take the channel of the depth above out of its medium."""
    cursor.pop()
    if placed:
        j = placed.pop()
        room[j] += sizes[order[len(placed)]]


def _overflow(sender: str, receiver: str, need: float, media: Sequence[Medium]) -> str:
    """Name the media of a pair whose channels cannot fit, and by how much."""
    links = [m for m in media if (m.sender, m.receiver) == (sender, receiver)]
    capacity = sum(m.capacity for m in links)
    names = ", ".join(describe(m) for m in links)
    if need > capacity:
        return (
            f"{names} overflows: the global channels from {sender} to {receiver} "
            f"need {fmt(need)}, {fmt(need - capacity)} more than it carries"
        )
    return (
        f"the global channels from {sender} to {receiver} (need {fmt(need)}) cannot be split "
        f"over {names} without overflowing one"
    )
