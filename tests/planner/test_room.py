"""What the media still have room for (cfgplan.planner.partial), and the
partitioned bound that leaves out expansions the media cannot carry
(media-tight, where a member cannot take both a raw image stream,
40, and its pose, 5, from one camera host over a medium of 40)."""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks.families import media_tight
from cfgplan.planner import Run, plan
from cfgplan.planner.bound import Bound
from cfgplan.planner.ground import ChannelSpec, Grounder, Numbering
from cfgplan.planner.grow import successors
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Channel, Partial, Room, root
from cfgplan.planner.partition import Partition
from cfgplan.problem import Problem
from tests.planner.problems import PROPERTY, load_text
from tests.planner.test_bound import least_completion
from tests.planner.test_scale import branch_and_bound, problem_of

DOMAIN = """\
(make-functionality :name '(sense ?r) :out '((d ?r)))
(make-config-method :name '(get ?r) :out '((?s (d ?r))) :body '((?s (sense ?r))))
"""
STATE = """(state (robot A) (robot B) (robot C)
       (medium wifi A B 40)
       (medium radio A C 30) (medium radio2 A C 30))
(goal (get A))
"""


@pytest.fixture
def room() -> Room:
    problem = load_text(DOMAIN, STATE)
    return Room(problem.task, Numbering())


def spec(sender: str, receiver: str, data: str, bandwidth: float | None) -> ChannelSpec:
    return ("global", (sender, receiver), 0, 1, (data, receiver), bandwidth)


def channel(sender: str, receiver: str, data: str, bandwidth: float | None) -> Channel:
    return Channel("global", (sender, receiver), 0, 1, (data, receiver), bandwidth)


def test_a_raw_stream_fits_alone_but_not_beside_a_pose(room: Room) -> None:
    raw = room.needs([spec("A", "B", "image", 40)])
    assert room.fits(raw, room.load([]))
    assert not room.fits(raw, room.load([channel("A", "B", "pose", 5)]))
    assert room.fits(raw, room.load([channel("A", "C", "pose", 5)]))  # another pair


def test_channels_that_may_merge_load_their_pair_once_by_the_largest(room: Room) -> None:
    """Two channels of one pair, kind and data may turn out one channel (4.5):
    the larger bandwidth counts, not the sum."""
    load = room.load([channel("A", "B", "image", 40), channel("A", "B", "image", 5)])
    assert room.fits(room.needs([spec("A", "B", "image", 40)]), load)
    assert not room.fits(room.needs([spec("A", "B", "map", 1)]), load)
    # Within one expansion too.
    twice = room.needs([spec("A", "B", "image", 30), spec("A", "B", "image", 40)])
    assert [n.bandwidth for n in twice] == [40]


def test_a_channel_is_never_split_over_two_media(room: Room) -> None:
    assert room.fits(room.needs([spec("A", "C", "x", 30), spec("A", "C", "y", 30)]), {})
    assert not room.fits(room.needs([spec("A", "C", "x", 40)]), {})  # 60 in all, 30 each


def test_a_global_channel_needs_a_medium_even_without_a_bandwidth(room: Room) -> None:
    assert not room.fits(room.needs([spec("B", "A", "x", None)]), {})  # none from B to A
    assert room.fits(room.needs([spec("A", "B", "x", None)]), room.load([]))
    # Not between two robots: no medium needed.
    assert room.needs([spec("A", "A", "x", 99)]) == ()
    local: ChannelSpec = ("local", ("A",), 0, 1, ("x", "A"), 99)
    assert room.needs([local]) == ()


def test_without_media_every_channel_fits() -> None:
    problem = load_text(DOMAIN, "(state (robot A) (robot B)) (goal (get A))")
    room = Room(problem.task, Numbering())
    assert room.needs([spec("A", "B", "x", 1000)]) == ()
    assert room.load([channel("A", "B", "x", 1000)]) == {}


def search_tree(problem: Problem, most: int) -> list[Partial]:
    """The first ``most`` nodes with a method on top, breadth first."""
    grounder = Grounder(problem.task)
    out: list[Partial] = []
    queue = [root(problem.goal_call)]
    while queue and len(out) < most:
        node = queue.pop(0)
        if node.done:
            continue
        if problem.task.is_method(node.stack[0].call):
            out.append(node)
        queue.extend(c for c in successors(grounder, node) if isinstance(c, Partial))
    return out


def test_the_media_raise_the_bound_but_never_past_the_cheapest_completion() -> None:
    """Below each of the first 150 nodes, the partitioned bound is at most the
    cheapest completion (a completion always fits the media: a node whose
    channels overflow them is a dead end, partial.py), at least the bound
    without the media test, and above it somewhere."""
    problem = problem_of(media_tight(4, 2, 1))
    grounder, bound = Grounder(problem.task), Bound(problem.task)
    partition = Partition(grounder)
    nodes = search_tree(problem, 150)
    with_room = [partition.estimate(node, bound.certain_agents(node)) for node in nodes]
    blind = Partition(grounder, media=False)
    raised = 0
    for node, estimate in zip(nodes, with_room, strict=True):
        truth = least_completion(grounder, node)
        without = blind.estimate(node, bound.certain_agents(node))
        if truth is None:
            continue
        assert estimate is not None and without is not None
        assert without <= estimate <= truth - node.cost + 1e-9
        raised += estimate > without
    assert raised > 0


@pytest.mark.parametrize(
    ("texts", "limit", "fewer"),
    [
        (media_tight(5, 2, 1), None, False),  # --all walks every derivation anyway
        (media_tight(5, 2, 1), 10, True),
        (media_tight(6, 4, 4), 20, True),
    ],
    ids=["media-tight-5-all", "media-tight-5-top10", "media-tight-6-top20"],
)
def test_leaving_out_what_the_media_cannot_carry_changes_no_ranked_list(
    texts: tuple[str, str], limit: int | None, fewer: bool
) -> None:
    """The same configurations in the same order (costs, identities, thesis
    order at equal cost) with the media test on and off; with it on, a
    best-first search takes fewer nodes."""
    problem = problem_of(texts)  # the plain search: parts would hide its nodes
    run = Run(problem.task, problem.goal_call, limit, options=SearchOptions(components=False))
    configs = list(run)
    nodes_with = run.stats.nodes
    problem = problem_of(texts)  # a new task: its bounds are made anew
    blind_options = SearchOptions(components=False, media=False)
    run = Run(problem.task, problem.goal_call, limit, options=blind_options)
    blind = list(run)
    assert len(configs) >= 10
    assert [(c.cost, c.identity(), c.derivation) for c in configs] == [
        (c.cost, c.identity(), c.derivation) for c in blind
    ]
    assert (nodes_with < run.stats.nodes) == fewer


@st.composite
def tight_media(draw: st.DrawFn) -> tuple[str, str]:
    """A small media-tight instance whose media are redrawn: each capacity
    from tight to loose, some media left out (no medium for that pair)."""
    n, cameras = draw(st.integers(2, 5)), draw(st.integers(0, 2))
    domain, state = media_tight(n, 2, cameras)

    def redraw(match: re.Match[str]) -> str:
        capacity = draw(st.sampled_from([None, 4, 5, 10, 40, 45, 100]))
        return "" if capacity is None else f"{match.group(1)} {capacity})"

    return domain, re.sub(r"(\(medium wifi \S+ \S+) 40\)", redraw, state)


@pytest.mark.quick(3)
@settings(PROPERTY, max_examples=40)
@given(tight_media())
def test_with_any_media_the_cheapest_is_branch_and_bounds_and_the_list_unchanged(
    texts: tuple[str, str],
) -> None:
    """Whatever the media: the cheapest configuration costs what branch and
    bound (without the partitioned bound) finds, and the five cheapest are
    the five the search lists with the media test off."""
    problem = problem_of(texts)
    found, _ = plan(problem.task, problem.goal_call, limit=5)
    least = branch_and_bound(problem)
    assert [c.cost for c in found[:1]] == ([] if least is None else [least])
    problem = problem_of(texts)
    blind, _ = plan(problem.task, problem.goal_call, limit=5, options=SearchOptions(media=False))
    assert [(c.cost, c.identity(), c.derivation) for c in found] == [
        (c.cost, c.identity(), c.derivation) for c in blind
    ]
