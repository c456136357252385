"""The canonical form of a node (cfgplan.planner.canonical): the node up to labels."""

from __future__ import annotations

from cfgplan.planner.canonical import canonical
from cfgplan.planner.ground import Grounder
from cfgplan.planner.partial import Item, root
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
