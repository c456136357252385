"""Property tests of the planner (thesis 4.5) on random small domains
(:mod:`tests.planner.generated`).

Properties (4.5 and the ranking of 6.3.2):

- ``plan(limit=1)`` returns the first configuration of ``plan(limit=None)``;
- the distinct list is the derivations list with repeats (equal
  ``identity()``) removed, first occurrences kept, in the same order;
- costs never decrease, and at equal cost derivation numbers increase;
- every configuration is admissible by the independent checker of
  :mod:`cfgplan.configuration.admissible`;
- the derivations are exactly those of :func:`tests.planner.oracle.depth_first`,
  a literal depth-first reading of 4.5, stably sorted by cost: the same
  configurations, costs and, at equal cost, the same (depth-first) order;
- the order of the state's facts changes no configuration: the same set,
  the same costs (only which of equal-cost configurations comes first);
- the bounds change nothing found: with the partitioned bound (and its media
  test) on every node, which a search this small would otherwise never
  compute, best-first lists the depth-first planner's first ``k``, and
  ``--all`` in windows by cost, halved again and again, lists them all.

Planner bugs found this way are kept as reproducers in ``test_reproducers.py``.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, replace
from itertools import pairwise
from random import Random
from unittest.mock import patch

import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

from cfgplan.configuration.admissible import problems
from cfgplan.configuration.model import Configuration
from cfgplan.planner import plan
from cfgplan.planner.options import SearchOptions
from cfgplan.planner.partial import Load, Need, Room
from cfgplan.planner.plan import Run, analysis
from cfgplan.planner.report import Condition
from tests.planner.generated import generated
from tests.planner.oracle import depth_first
from tests.planner.problems import FIRST_NODE, PROPERTY, Generated, load_generated, run, solve


@pytest.mark.quick(5)
@PROPERTY
@given(generated())
def test_limit_k_is_a_prefix_of_all(example: Generated) -> None:
    """``-k N`` lists the first N of ``--all``, labels and derivation numbers
    included, each search from the task read afresh, as the CLI's
    (a search leaves caches on its task)."""
    for distinct in (True, False):
        everything = run(solve(example), distinct=distinct)
        for k in (1, 2, 3, 5):
            first = run(solve(example), limit=k, distinct=distinct)
            assert first == everything[:k], (distinct, k)


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
def test_distinct_is_derivations_without_repeats(example: Generated) -> None:
    problem = solve(example)
    derivations = run(problem, distinct=False)
    distinct = run(problem, distinct=True)
    seen: set[object] = set()
    expected: list[Configuration] = []
    for config in derivations:
        if config.identity() not in seen:
            seen.add(config.identity())
            expected.append(config)
    assert [(c.cost, c.identity()) for c in distinct] == [(c.cost, c.identity()) for c in expected]

    # Labels and channel order too. Derivation numbers differ: in distinct mode the
    # search skips partial configurations reached again, so it completes fewer.
    def unnumbered(configs: list[Configuration]) -> list[Configuration]:
        return [c.model_copy(update={"derivation": 0}) for c in configs]

    assert unnumbered(distinct) == unnumbered(expected)


@pytest.mark.quick(5)
@PROPERTY
@given(generated())
def test_ranked_by_cost_then_derivation(example: Generated) -> None:
    problem = solve(example)
    derivations = run(problem, distinct=False)
    distinct = run(problem, distinct=True)
    assert [c.derivation for c in derivations] == list(range(1, len(derivations) + 1))
    for configs in (derivations, distinct):
        for before, after in pairwise(configs):
            assert before.cost <= after.cost
            if before.cost == after.cost:
                assert before.derivation < after.derivation


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
def test_every_configuration_is_admissible(example: Generated) -> None:
    problem = solve(example)
    for config in run(problem, distinct=False):
        assert problems(config, problem.domain, problem.state, example.weights) == [], str(
            config.derivation
        )


@pytest.mark.quick(20)
@PROPERTY
@given(generated())
def test_same_derivations_as_depth_first(example: Generated) -> None:
    """The planner returns exactly the derivations of the thesis's depth-first
    planner, cheapest first and, at equal cost, in depth-first order (6.3.2)."""
    problem = solve(example)
    derivations = run(problem, distinct=False)
    assert [(c.cost, c.identity()) for c in derivations] == depth_first(problem, example.weights)


@pytest.mark.quick(20)
@PROPERTY
@given(generated(uncertain=True), st.integers(1, 6))
def test_reliability_ranks_as_depth_first(example: Generated, k: int) -> None:
    """With ``--weights reliability=W`` (7.2) the cost adds W·(−ln p) for each
    functionality and each global channel between two robots (p of the most
    reliable medium): costs with no unit, ranked to 11 significant digits
    (:mod:`cfgplan.planner.costs`). All derivations, and the first ``k``
    with both bounds on every node, are the depth-first planner's."""
    problem = solve(example)
    oracle = depth_first(problem, example.weights)
    derivations = run(problem, distinct=False)
    assert [(c.cost, c.identity()) for c in derivations] == oracle
    first = run(problem, limit=k, distinct=False, options=FIRST_NODE)
    assert [(c.cost, c.identity()) for c in first] == oracle[:k]


@pytest.mark.quick(5)
@PROPERTY
@given(generated(), st.integers(1, 6))
def test_the_bounds_change_nothing_found(example: Generated, k: int) -> None:
    """The ``k`` cheapest, best first with both bounds on every node, are the
    first ``k`` of the depth-first planner (derivations), and of the distinct
    list planned without them."""
    problem = solve(example)
    derivations = run(problem, limit=k, distinct=False, options=FIRST_NODE)
    distinct = run(problem, limit=k, distinct=True, options=FIRST_NODE)
    oracle = depth_first(problem, example.weights)
    assert [(c.cost, c.identity()) for c in derivations] == oracle[:k]
    assert distinct == run(problem, distinct=True)[:k]


@pytest.mark.quick(5)
@PROPERTY
@given(generated(), st.integers(1, 4))
def test_all_in_windows_lists_everything(example: Generated, held: int) -> None:
    """``--all`` as on a large instance: the first walk given up at once for
    windows by cost, priced by both bounds, each window holding at most
    ``held`` configurations (its upper edge lowered again and again). The
    derivations are the depth-first planner's, the distinct list the one
    walk's. (Found this way: configurations a window dropped when it was
    halved were never listed again.)"""
    problem = solve(example)
    whole = run(problem, distinct=True)
    halved = replace(FIRST_NODE, one_pass=0, most_held=held)
    derivations = run(problem, distinct=False, options=halved)
    distinct = run(problem, distinct=True, options=halved)
    assert [(c.cost, c.identity()) for c in derivations] == depth_first(problem, example.weights)
    assert distinct == whole


# -- the order of facts -------------------------------------------------------------------

FACT = re.compile(r"[\w-]+\([^()]*\)")


def with_facts_shuffled(example: Generated, order: Random) -> Generated:
    """The same example with the state's facts in another order."""
    head, end, rest = example.state.partition(")\n\n")
    facts = FACT.findall(head)
    order.shuffle(facts)
    return Generated(example.domain, f"(state {', '.join(facts)}{end}{rest}", example.weights)


def ranked(configs: list[Configuration]) -> tuple[list[float], Counter[tuple[float, object]]]:
    """What fact order must not change: the costs in rank order and the
    configurations with their costs (as a multiset: derivations may repeat)."""
    return [c.cost for c in configs], Counter((c.cost, c.identity()) for c in configs)


@pytest.mark.quick(5)
@PROPERTY
@given(generated(), st.randoms(use_true_random=False))
def test_fact_order_changes_no_configuration(example: Generated, order: Random) -> None:
    """A state is a set of facts (4.4): reordering them may only reorder
    configurations of equal cost (the depth-first order of 6.3.2 takes facts
    in state order), never add, lose or re-cost one."""
    shuffled = with_facts_shuffled(example, order)
    assert sorted(FACT.findall(shuffled.state)) == sorted(FACT.findall(example.state))
    first, second = solve(example), solve(shuffled)
    for distinct in (True, False):
        assert ranked(run(first, distinct=distinct)) == ranked(run(second, distinct=distinct))


# -- the generator covers what it should ----------------------------------------------


@dataclass(frozen=True)
class Coverage:
    """What one generated example exercised."""

    derivations: int
    distinct: int
    media: bool  # a configuration has channels assigned to media
    rewired_in: bool  # the action or every processor reached through :in ports
    cycle: bool  # a derivation was rejected for a cycle (a self-loop re-wired)
    located: bool  # a configuration holds the localizer with a bound output
    fan_out: bool  # a configuration holds the monitor fed through do-act's :in
    repeated_channel: bool  # a channel written twice, and configurations found
    repeated_call: bool  # a call twice in a body, and configurations found
    raised: bool  # the partitioned bound, on from the first node, raised a priority
    media_cut: bool  # ... and left out an expansion the media cannot carry (partial.py)
    replayed: bool  # a ranked search replayed a sub-derivation (grow.py), and listed


def _coverage(example: Generated) -> Coverage:
    problem = load_generated(example)  # the files, through cfgplan.problem.load
    fast = solve(example)  # what the properties use is the same problem
    assert fast.domain.model_dump() == problem.domain.model_dump()
    assert fast.state.model_dump() == problem.state.model_dump()
    assert fast.goal_call == problem.goal_call
    derivations, search = plan(problem.task, problem.goal_call, limit=None, distinct=False)
    names = {f.name for c in derivations for f in c.functionalities}
    text = example.domain
    wrapped = "(?f0 (do-act" in text or ("(?f0 (w" in text and "(?f0 (p" not in text)
    channels = re.findall(r"\(\((?:local|global) [^()]*\) [^()]*\([^()]*\)", text)
    room = analysis(problem.task).partition.room
    cut: list[bool] = []

    def fits(needs: tuple[Need, ...], load: Load) -> bool:
        cut.append(not Room.fits(room, needs, load))
        return not cut[-1]

    with patch.object(room, "fits", fits):
        bounded = Run(problem.task, problem.goal_call, limit=3, distinct=False, options=FIRST_NODE)
        list(bounded)
    replaying = Run(
        problem.task, problem.goal_call, 6, options=SearchOptions(replay_least=1, replay_worth=0)
    )
    replayed = bool(list(replaying)) and replaying.stats.replays > 0
    return Coverage(
        derivations=len(derivations),
        distinct=len({c.identity() for c in derivations}),
        media=any(c.media for c in derivations),
        rewired_in=wrapped,
        cycle=any(d.condition is Condition.CYCLE for d in search.report.rejected),
        located="loc" in names,
        fan_out="mon" in names,
        repeated_channel=bool(derivations) and len(channels) > len(set(channels)),
        repeated_call=bool(derivations) and "(?t2 " in text,
        raised=bounded.strategy.pricer.raised > 0,
        media_cut=any(cut),
        replayed=replayed,
    )


@pytest.mark.slow
def test_the_generator_covers_what_it_should() -> None:
    """The generated problems load as files do, and exercise what they should."""
    seen: list[Coverage] = []

    @settings(PROPERTY, max_examples=100, phases=[Phase.generate])
    @given(generated())
    def collect(example: Generated) -> None:
        seen.append(_coverage(example))

    collect()
    solvable = [s for s in seen if s.derivations]
    assert 0.25 < len(solvable) / len(seen) < 0.9  # often, not always solvable
    assert any(s.distinct >= 3 for s in seen)  # several configurations
    assert any(s.derivations > s.distinct for s in solvable)  # repeated derivations
    assert any(s.media for s in seen)
    assert any(s.rewired_in for s in solvable)
    assert any(s.cycle for s in seen)
    assert any(s.located for s in seen)
    assert any(s.fan_out for s in seen)
    assert any(s.repeated_channel for s in seen)
    assert any(s.repeated_call for s in seen)
    assert any(s.raised for s in seen)
    assert any(s.media_cut for s in seen)
    assert sum(s.replayed for s in seen) >= 10
