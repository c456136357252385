"""The node and the steps that grow it (cfgplan.planner.partial; 4.5, steps 2a and 3)."""

from __future__ import annotations

from dataclasses import replace

from cfgplan.planner.ground import ChannelSpec, Effects, Expansion, Grounder, Numbering
from cfgplan.planner.partial import (
    Channel,
    Item,
    Partial,
    expand_method,
    place_functionality,
    reuse_functionality,
    root,
)
from cfgplan.planner.report import Condition, DeadEnd
from cfgplan.planner.task import Task
from tests.planner.problems import load_text

DOMAIN = """\
(make-functionality :name '(cam ?r) :out '((img ?r)))
(make-functionality :name '(use ?r ?o) :in '((img ?o)))
(make-config-method :name '(go ?r) :precond '((robot ?r))
  :channels '(((local ?r) ?a ?b (img ?r))) :body '((?a (cam ?r)) (?b (use ?r ?r))))
"""


def task() -> Task:
    return load_text(DOMAIN, "(state (robot A) (robot B)) (goal (go A))").task


def made(
    size: int,
    channels: tuple[ChannelSpec, ...],
    body: tuple[tuple[str, ...], ...],
    outputs: dict[tuple[str, ...], tuple[int, float | None]],
    inputs: dict[tuple[str, ...], tuple[int, ...]],
    effects: Effects = (),
) -> Expansion:
    """An expansion built by hand, numbered as the grounder numbers one."""
    number = Numbering()
    return Expansion(
        size,
        channels,
        body,
        outputs,
        inputs,
        effects,
        channel_numbers=tuple(number((k, r, d, bw)) for k, r, _, _, d, bw in channels),
        body_numbers=tuple(number((call, frozenset())) for call in body),
        number=number,
    )


def with_channels(node: Partial, *channels: Channel, stack: tuple[Item, ...] = ()) -> Partial:
    return replace(node, channels=channels, stack=stack or node.stack)


def local(
    source: int, target: int, data: tuple[str, ...], bandwidth: float | None = None
) -> Channel:
    return Channel("local", ("A",), source, target, data, bandwidth)


def test_rewiring_moves_both_ends_of_a_channel_at_the_expanded_instance() -> None:
    """Step 3d: the sending end through :out, the receiving end through :in
    (to every body item an :in entry names: fan-out), both for a self-loop."""
    node = root(("m", "A"))
    d = ("d", "A")
    node = with_channels(node, local(9, 1, d), local(1, 1, d), local(1, 8, d))
    expansion = made(
        size=2,
        channels=(),
        body=(("flt", "A"), ("mon", "A")),
        outputs={d: (0, None)},
        inputs={d: (0, 1)},
    )
    child = expand_method(node, node.stack[0], expansion, None, 0)
    assert isinstance(child, Partial)
    ends = [(ch.source, ch.target) for ch in child.channels]
    assert ends == [(9, 2), (9, 3), (2, 2), (2, 3), (2, 8)]
    assert child.next_label == 4 and child.path == (0,)


def test_rewiring_a_global_channel_takes_the_bandwidth_of_the_out_entry() -> None:
    node = root(("m", "A"))
    d = ("d", "A")
    node = with_channels(node, Channel("global", ("A", "B"), 1, 7, d, None))
    expansion = made(1, (), (("flt", "A"),), {d: (0, 20.0)}, {}, ())
    child = expand_method(node, node.stack[0], expansion, None, 0)
    assert isinstance(child, Partial)
    assert child.channels[0].bandwidth == 20.0


def test_a_channel_no_out_entry_produces_is_a_dead_end() -> None:
    node = with_channels(root(("m", "A")), local(1, 7, ("d", "A")))
    expansion = made(1, (), (("flt", "A"),), {}, {}, ())
    dead = expand_method(node, node.stack[0], expansion, None, 0)
    assert isinstance(dead, DeadEnd)
    assert dead.condition is Condition.INFORMATION
    assert dead.reason == "no :out entry produces (d A)"


def place(t: Task, node: Partial, call: tuple[str, ...]) -> Partial | DeadEnd:
    schema = t.functionality(call)
    assert schema is not None
    (instance,) = Grounder(t).instances(schema, call)
    return place_functionality(node, node.stack[0], schema, instance, None, t)


def test_placing_both_ends_resolves_and_costs_the_channel() -> None:
    t = task()
    img = ("img", "A")
    node = with_channels(
        root(("x",)),
        local(2, 3, img),
        stack=(Item(2, ("cam", "A"), frozenset()), Item(3, ("use", "A", "A"), frozenset())),
    )
    first = place(t, node, ("cam", "A"))
    assert isinstance(first, Partial)
    assert first.cost == 10 + 1  # a robot and a functionality; the channel waits
    second = place(t, first, ("use", "A", "A"))
    assert isinstance(second, Partial)
    assert second.cost == 10 + 2 + 1 and second.resolved == {("local", 2, 3, img)}


def test_a_local_channel_between_two_robots_is_a_dead_end() -> None:
    t = task()
    img = ("img", "B")
    node = with_channels(
        root(("x",)),
        local(2, 3, img),
        stack=(Item(2, ("cam", "B"), frozenset()), Item(3, ("use", "A", "B"), frozenset())),
    )
    first = place(t, node, ("cam", "B"))
    assert isinstance(first, Partial)
    dead = place(t, first, ("use", "A", "B"))
    assert isinstance(dead, DeadEnd)
    assert dead.condition is Condition.LOCATION
    assert dead.reason == "declared (local A) but it runs from cam(B) on B to use(A, B) on A"


def test_reuse_moves_channels_and_merges_identical_ones_keeping_the_larger_bandwidth() -> None:
    """Step 2a: cam(A) is already F2; the second instance (label 4) is not
    added, its channel moves to F2 and merges with the identical F2 -> F3."""
    t = task()
    img = ("img", "A")
    node = with_channels(
        root(("x",)),
        local(2, 3, img, 5.0),
        local(4, 3, img, 9.0),
        stack=(
            Item(2, ("cam", "A"), frozenset()),
            Item(3, ("use", "A", "A"), frozenset()),
            Item(4, ("cam", "A"), frozenset()),
        ),
    )
    placed = place(t, node, ("cam", "A"))
    assert isinstance(placed, Partial)
    placed = place(t, placed, ("use", "A", "A"))
    assert isinstance(placed, Partial)
    reused = reuse_functionality(placed, placed.stack[0], 2, t)
    assert isinstance(reused, Partial)
    assert [(c.source, c.target, c.bandwidth) for c in reused.channels] == [(2, 3, 9.0)]
    assert reused.cost == placed.cost  # nothing new: the channel was there already
