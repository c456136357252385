"""The canonical form of a node (cfgplan.planner.partial): the node up to labels."""

from __future__ import annotations

import copy

import pytest

from benchmarks.families import conversion
from cfgplan.planner.finish import fingerprint
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import successors
from cfgplan.planner.partial import Item, Partial, canonical, root
from tests.backends.support import DOMAINS
from tests.planner.problems import load_text
from tests.planner.test_partial import local, task, with_channels


def test_canonical_forgets_labels() -> None:
    img = ("img", "A")
    stack = (Item(2, ("cam", "A"), frozenset()), Item(3, ("use", "A", "A"), frozenset()))
    one = with_channels(root(("x",)), local(2, 3, img), stack=stack)
    relabelled = (Item(7, ("cam", "A"), frozenset()), Item(5, ("use", "A", "A"), frozenset()))
    other = with_channels(root(("x",)), local(7, 5, img), stack=relabelled)
    g = Grounder(task())
    assert canonical(one, g) == canonical(other, g)
    swapped = with_channels(root(("x",)), local(5, 7, img), stack=relabelled)
    assert canonical(one, g) != canonical(swapped, g)


def _reached(domain: str, state: str, most: int) -> tuple[Grounder, list[Partial]]:
    """The first ``most`` nodes the planner's step reaches from the goal, breadth first."""
    problem = load_text(domain, state)
    grounder = Grounder(problem.task)
    found: list[Partial] = []
    todo = [root(problem.goal_call)]
    while todo and len(found) < most:
        node = todo.pop(0)
        found.append(node)
        if not node.done:
            todo += [c for c in successors(grounder, node) if isinstance(c, Partial)]
    return grounder, found


@pytest.mark.parametrize("family", ["cross-door", "conversion"])
def test_items_are_numbered_when_made_and_canonical_only_reads_nodes(family: str) -> None:
    """Nodes are never written after they are made: canonical() and
    fingerprint() leave every node as it was, and each item's and channel's
    number, given when it was made, is what the canonical form defines: an
    item's call with its ancestors whose method can recur (those with some
    are numbered by canonical() itself), a channel's kind, robots, data and
    bandwidth. The conversion graph recurses, so there the ancestors count."""
    domain, state = conversion(4) if family == "conversion" else _cross_door()
    grounder, nodes = _reached(domain, state, 300)
    recursive = grounder.task.recursive
    before = copy.deepcopy(nodes)
    for node in nodes:
        canonical(node, grounder)
        if node.done:
            fingerprint(node, grounder.numbering)
    assert nodes == before
    number = grounder.numbering
    checked = 0
    for node in nodes:
        for item in node.stack:
            relevant = frozenset(a for a in item.ancestors if (a[0], len(a) - 1) in recursive)
            assert item.relevant == relevant
            if relevant or item.label == 1:  # numbered by canonical() (the goal: by root())
                assert item.number == -1
                checked += 1
            else:
                assert item.number == number((item.call, relevant))
        for ch in node.channels:
            assert ch.number == number((ch.kind, ch.robots, ch.data, ch.bandwidth))
    assert checked > len(nodes) or family != "conversion"  # many had recursive ancestors


def _cross_door() -> tuple[str, str]:
    """Thesis 6.2.2, step 1."""
    folder = DOMAINS / "cross-door"
    return (folder / "domain.lisp").read_text(), (folder / "state-6.2.2-step1.lisp").read_text()
