"""Searches over the user's input without recursion.

:func:`cfgplan.configuration.media.assign` backtracks over the global channels
and :func:`cfgplan.configuration.matching.satisfying` over the atoms of a
precondition; both used to recurse once per item, so 3,000 channels or
precondition atoms overflowed Python's stack. They now keep an explicit stack;
on small inputs they give exactly what the recursive versions (kept here as
references) gave, in the same order.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from hypothesis import given, settings
from hypothesis import strategies as st

from cfgplan.configuration.matching import Env, Ground, atom_of, satisfying, unify
from cfgplan.configuration.media import Demand, MediaResult, assign
from cfgplan.ir.model import Atom, Medium

FUZZ = settings(max_examples=300, derandomize=True, database=None, deadline=None)


def reference_assign(demands: Sequence[Demand | None], media: Sequence[Medium]) -> MediaResult:
    """The recursive search cfgplan had before it was made iterative."""
    todo = [i for i, d in enumerate(demands) if d is not None]
    for i in todo:
        d = demands[i]
        assert d is not None
        if not any(m.sender == d.sender and m.receiver == d.receiver for m in media):
            return MediaResult(None, "no medium")
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
        return MediaResult(dict(sorted(chosen.items())))
    return MediaResult(None, "overflow")


ROBOTS = ["Pippi", "Emil", "Rasmus"]
_demand = st.one_of(
    st.none(),
    st.builds(
        Demand, st.sampled_from(ROBOTS), st.sampled_from(ROBOTS), st.integers(0, 30).map(float)
    ),
)
_medium = st.builds(
    lambda s, r, c: Medium(type="socket", sender=s, receiver=r, capacity=c),
    st.sampled_from(ROBOTS),
    st.sampled_from(ROBOTS),
    st.integers(0, 60).map(float),
)


@FUZZ
@given(st.lists(_demand, max_size=8), st.lists(_medium, max_size=5))
def test_assign_finds_what_the_recursive_search_found(
    demands: list[Demand | None], media: list[Medium]
) -> None:
    """Both are exact: one finds an assignment exactly when the other does (which
    one may differ: any assignment that fits will do, 4.6)."""
    ours, theirs = assign(demands, media), reference_assign(demands, media)
    assert ours.ok == theirs.ok
    if ours.assignment is not None:
        assert all(m.capacity >= x for m, x in zip(media, loads(ours, demands, media), strict=True))
        for i, j in ours.assignment.items():
            d = demands[i]
            assert d is not None and (media[j].sender, media[j].receiver) == (d.sender, d.receiver)


def loads(result: MediaResult, demands: list[Demand | None], media: list[Medium]) -> list[float]:
    out = [0.0] * len(media)
    for i, j in (result.assignment or {}).items():
        d = demands[i]
        assert d is not None
        out[j] += d.bandwidth
    return out


def test_assign_thousands_of_channels() -> None:
    media = [Medium(type="socket", sender="Emil", receiver="Pippi", capacity=3000.0)] * 2
    demands: list[Demand | None] = [Demand("Emil", "Pippi", 1.0)] * 5000
    result = assign(demands, media)
    assert result.ok and result.assignment is not None
    assert sorted(loads(result, demands, media)) == [2000.0, 3000.0]
    assert not assign([*demands, Demand("Emil", "Pippi", 1.0)] * 2, media).ok


def reference_satisfying(
    atoms: Sequence[Ground], facts: Sequence[Ground], env: Env
) -> Iterator[Env]:
    def extend(index: int, current: Env) -> Iterator[Env]:
        if index == len(atoms):
            yield current
            return
        for fact in facts:
            bound = unify(atoms[index], fact, current)
            if bound is not None:
                yield from extend(index + 1, bound)

    yield from extend(0, env)


_term = st.sampled_from(["?x", "?y", "?z", "a", "b", "c"])
_fact = st.tuples(st.sampled_from(["p", "q"]), st.sampled_from("abc"), st.sampled_from("abc"))
_pattern = st.tuples(st.sampled_from(["p", "q"]), _term, _term)


@FUZZ
@given(st.lists(_pattern, max_size=4), st.lists(_fact, max_size=6))
def test_satisfying_gives_the_recursive_bindings_in_order(
    patterns: list[tuple[str, str, str]], facts: list[tuple[str, str, str]]
) -> None:
    atoms = [Atom(predicate=p, args=args) for p, *args in patterns]
    ours = list(satisfying(atoms, facts, {}))
    theirs = list(reference_satisfying([atom_of(a) for a in atoms], facts, {}))
    assert ours == theirs


def test_satisfying_a_precondition_of_thousands_of_atoms() -> None:
    atoms = [Atom(predicate="robot", args=(f"?r{i}",)) for i in range(3000)]
    (env,) = satisfying(atoms, [("robot", "Pippi")], {})
    assert len(env) == 3000 and set(env.values()) == {"Pippi"}
