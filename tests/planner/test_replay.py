"""Replays of closed sub-derivations (cfgplan/planner/grow.py).

The claims, each tested where it can fail:

- a replay is the node the step-by-step walk with the record's choices
  reaches: the same stack, C, channels (numbers and bandwidths included),
  postconditions, labels, path and cost;
- a deviating node's floor is at most what its cheapest derivation costs;
- the best-first search lists the same configurations, labels and
  derivation numbers with replays as without, on the shared sub-derivations
  of the ``dag`` family and on generated problems;
- on ``dag`` the optimum is found in a number of nodes linear in D (the
  walk alone has a Fibonacci number of steps).
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from hypothesis import given

from benchmarks.families import dag
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import Grower, filtered, replay, successors
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.plan import Run, growing
from cfgplan.planner.pricer import Pricer
from cfgplan.planner.search import BestFirst
from cfgplan.problem import Problem
from tests.planner.generated import generated
from tests.planner.problems import PROPERTY, Generated, load_text, solve

EVERY = SearchOptions(replay_least=1, replay_worth=0)
"""Replay every sub-derivation closed, however short (small domains' are)."""

NODE_FIELDS = (
    "stack",
    "placed",
    "labels",
    "located",
    "channels",
    "effects",
    "next_label",
    "path",
    "cost",
    "robots",
    "resolved",
)


def _settled(grounder: Grounder, node: Partial) -> Partial | None:
    """Place the functionalities on top: in a replayed walk each is in C
    already, so each has one child (reused), or none (a dead end: a channel
    on the wrong robot)."""
    task = grounder.task
    while node.stack and not task.is_method(node.stack[0].call):
        children = [c for c in successors(grounder, node) if isinstance(c, Partial)]
        assert len(children) <= 1
        if not children:
            return None
        node = children[0]
    return node


def walked(grounder: Grounder, node: Partial, choices: tuple[int, ...]) -> Partial | None:
    """``node`` grown step by step (4.5) along ``choices``; None at a dead end."""
    for choice in choices:
        depth = len(node.path)
        chosen = [
            c
            for c in successors(grounder, node)
            if isinstance(c, Partial) and len(c.path) > depth and c.path[depth] == choice
        ]
        if not chosen:
            return None
        settled = _settled(grounder, chosen[0])
        if settled is None:
            return None
        node = settled
    return node


def explored(problem: Problem, most: int) -> Iterator[tuple[Grower, Pricer, Partial]]:
    """The first ``most`` nodes a replaying grower makes, breadth first."""
    grower, pricer = growing(problem.task, EVERY, replays=True)
    todo = [node for _, node in grower.settle(root(problem.goal_call), pricer)]
    made = 0
    while todo and made < most:
        node = todo.pop(0)
        made += 1
        yield grower, pricer, node
        if not node.done:
            todo.extend(child for _, child in grower.children(node, pricer))


def check_replays(problem: Problem, most: int = 400) -> tuple[int, int]:
    """Compare every replay made on the first ``most`` nodes with the walk,
    and every deviating node's floor with its cheapest derivation; how many
    of each were compared."""
    replays = floors = 0
    for grower, _, node in explored(problem, most):
        if node.done or node.memory is None or node.deviates:
            continue
        item = node.stack[0]
        record = node.memory.records.get(item.call)
        if record is None or item.call in item.ancestors:
            continue
        made = replay(node, item, record, grower.grounder)
        if made is None:
            continue  # the walk meets a dead end, or merges in another order
        walk = walked(grower.grounder, node, record.flat)
        settled = _settled(grower.grounder, made)
        assert walk is not None and settled is not None
        for name in NODE_FIELDS:
            assert getattr(settled, name) == getattr(walk, name), name
        replays += 1
    for grower, pricer, node in explored(problem, most):
        if node.deviates:
            assert node.floor <= cheapest(grower, pricer, node)
            floors += 1
    return replays, floors


def cheapest(grower: Grower, pricer: Pricer, node: Partial) -> float:
    """The cheapest derivation below ``node``, searched without a bound and
    without replays (infinite when there is none)."""
    plain = Grower(grower.grounder, distinct=False)
    unbounded = Pricer(pricer.levels, _nothing, stats=plain.stats)
    for config in BestFirst(plain, unbounded, node.stack[0].call, origin=node):
        return config.cost
    return float("inf")


def _nothing(node: Partial) -> float:
    return 0.0


@pytest.mark.parametrize("depth", [4, 6])
def test_a_replay_is_the_walk_and_a_floor_is_below_its_derivations(depth: int) -> None:
    """Shared sub-derivations (benchmarks/families/shared.py ``dag``): each
    level's second occurrence is replayed; the replay equals the walk."""
    replays, floors = check_replays(load_text(*dag(depth)))
    assert replays >= depth - 2 and floors >= 1


@pytest.mark.parametrize("depth", [6, 9])
def test_replays_list_what_the_walk_lists(depth: int) -> None:
    """``-k 8`` on ``dag``, with and without replays: the same configurations,
    labels and derivation numbers, distinct and every derivation."""
    for distinct in (True, False):
        found = []
        for replays in (True, False):
            problem = load_text(*dag(depth))
            options = EVERY if replays else SearchOptions(replays=False)
            run = Run(problem.task, problem.goal_call, 8, distinct, options=options)
            found.append(([c.model_dump() for c in run], run.stats))
        (listed, stats), (walked_list, plain) = found
        assert listed == walked_list
        assert stats.replays > 0 and stats.nodes < plain.nodes


def test_the_cheapest_on_dag_takes_nodes_linear_in_its_depth() -> None:
    """Without replays the walk of the optimum has a Fibonacci number of
    steps (exponential in D); with them each level costs a few
    nodes: one expansion of its first occurrence, one replay of its second."""
    nodes = {}
    for depth in (12, 16, 20):
        problem = load_text(*dag(depth))
        run = Run(problem.task, problem.goal_call, 1)
        assert [c.cost for c in run] == [3 * depth + 14]  # 10 for the robot
        # The second occurrences of levels 0 .. D-2; not those of levels 0 and 1,
        # whose walks (1 and 2 expansions) are shorter than SearchOptions.replay_least.
        assert SearchOptions().replay_least == 4
        assert run.stats.replays == depth - 3
        nodes[depth] = run.stats.nodes
    assert nodes[20] - nodes[16] == nodes[16] - nodes[12] <= 4 * 4


def test_a_forbidden_run_is_followed_then_dropped() -> None:
    """A child that follows a forbidden run keeps what is left of it; one
    that chose otherwise is free; one that followed it to its end is gone
    (it is the replay, listed beside)."""
    parent = root(("goal",)).but(path=(0,), forbidden=((1, 2, 3),))
    follows = filtered(parent, root(("goal",)).but(path=(0, 1, 2)))
    assert follows is not None and follows.forbidden == ((3,),)
    free = filtered(parent, root(("goal",)).but(path=(0, 1, 0)))
    assert free is not None and free.forbidden == ()
    assert filtered(parent, root(("goal",)).but(path=(0, 1, 2, 3))) is None


@pytest.mark.quick(10)
@given(generated())
@PROPERTY
def test_replays_change_nothing_found(example: Generated) -> None:
    """On generated problems (a body may call one method twice): every replay
    equals its walk, every floor is below its node's derivations, and
    ``-k 6`` lists what it lists without replays, distinct or not."""
    check_replays(solve(example), most=150)
    for distinct in (True, False):
        found = []
        for options in (EVERY, SearchOptions(replays=False)):
            problem = solve(example)
            run = Run(problem.task, problem.goal_call, 6, distinct, options=options)
            found.append([c.model_dump() for c in run])
        assert found[0] == found[1]
