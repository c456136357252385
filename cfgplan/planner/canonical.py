"""The canonical form of a search node: the node up to labels, as a short
digest (thesis 4.5 builds the same partial configuration along different
orders of choices; the search expands each form once, :mod:`cfgplan.planner.search`).

Nodes share most of their items, placed instances and channels: each one is
numbered when it is made (:class:`cfgplan.planner.ground.Expansion` carries
the numbers), so these functions only read nodes, never write them. The root
item, an item below a recursive method (its number depends on those
ancestors, and most children made are never taken), and items or channels
built by hand (tests) have none (-1): it is looked up here each time.
"""

from __future__ import annotations

import hashlib
from array import array

from cfgplan.planner.ground import Grounder
from cfgplan.planner.numbering import Numbering
from cfgplan.planner.partial import Partial
from cfgplan.planner.wiring import Channel


def placed_names(node: Partial) -> dict[int, int]:
    """Each placed instance's call, numbered, by label."""
    return {p.label: p.name for p in node.placed}


def channel_number(channel: Channel, number: Numbering) -> int:
    """The channel's kind, robots, data and bandwidth, numbered: made with
    it (:attr:`cfgplan.planner.wiring.Channel.number`) or looked up now."""
    found = channel.number
    if found < 0:
        found = number((channel.kind, channel.robots, channel.data, channel.bandwidth))
    return found


def channel_numbers(node: Partial, names: dict[int, int], number: Numbering) -> list[int]:
    """Each channel with its ends named by ``names``, numbered as a whole
    (one number to sort), in the node's order."""
    get = number.numbers.get
    out = []
    for ch in node.channels:
        numbered = ch.number  # (most are numbered when made: no call then)
        if numbered < 0:
            numbered = channel_number(ch, number)
        key = (numbered, names[ch.source], names[ch.target])
        found = get(key)
        out.append(number(key) if found is None else found)
    return out


def digest(numbers: list[int]) -> bytes:
    """A list of numbers as a 128-bit BLAKE2 digest: two different lists share
    one with odds of about 2^-128 per pair, far below anything a run can meet."""
    return hashlib.blake2b(array("q", numbers).tobytes(), digest_size=16).digest()


def canonical(node: Partial, grounder: Grounder) -> bytes:
    """The node up to labels — placed instances, channels, stack and P — as a
    128-bit :func:`digest`. Two nodes with the same canonical form have the
    same completions (up to labels). An item's ancestors count only where they
    can matter: those whose method can recur (:attr:`Task.recursive`, kept as
    :attr:`cfgplan.planner.partial.Item.relevant`); in a domain without
    recursion the order in which items were reached is forgotten. It takes 16
    bytes where the form takes kilobytes, so every expanded node can be
    remembered."""
    number = grounder.numbering
    names = placed_names(node)
    placed = sorted(p.number for p in node.placed)
    for index, item in enumerate(node.stack):
        names[item.label] = -1 - index
    channels = channel_numbers(node, names, number)
    channels.sort()
    stack = [
        item.number if item.number >= 0 else number((item.call, item.relevant))
        for item in node.stack
    ]
    get = number.numbers.get
    effects = []
    for effect in node.effects:
        found = get(effect)
        effects.append(number(effect) if found is None else found)
    effects.sort()
    # The lengths of the first three parts make the list say where each ends.
    return digest([len(placed), *placed, len(channels), *channels, len(stack), *stack, *effects])
