"""The FIFO sort of 5.1."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cfgplan.backends.sort import sort_functionalities
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.diagnostics import CfgplanError
from tests.backends.support import (
    THESIS_FUNCTIONALITIES,
    THESIS_SORTED,
    cross_door_44,
    thesis_labels,
)


def _config(
    functionalities: list[tuple[str, str]], channels: list[tuple[str, str]]
) -> Configuration:
    """Functionalities (label, name) on robot R; local channels (source, target)."""
    return Configuration(
        functionalities=tuple(
            FunctionalityInstance(label=lab, name=n, args=("R",)) for lab, n in functionalities
        ),
        channels=tuple(
            Channel(
                kind="local",
                source=s,
                target=t,
                source_robot="R",
                target_robot="R",
                data=("d", s, t),
            )
            for s, t in channels
        ),
        cost=0,
    )


def test_thesis_order_of_5_4() -> None:
    """5.4: from the list order F109, F113, F129, F118, F117, F116, F115, F114
    the algorithm gives F117, F116, F114, F129, F118, F115, F113, F109."""
    _, config = cross_door_44()
    labels = thesis_labels(config)
    # the premise: the planner lists the functionalities as the thesis does (4.6)
    assert [f.label for f in config.functionalities] == [
        labels[t] for t, _ in THESIS_FUNCTIONALITIES
    ]
    order = sort_functionalities(config)
    assert [f.label for f in order] == [labels[t] for t in THESIS_SORTED]


def test_cyclic_scan_continues_after_the_last_pick() -> None:
    """List order A, Y, X, B with channels A -> B and X -> Y: after X the scan
    goes on with B (after X), then wraps to Y. Restarting at the head of the
    list each time would give A, X, Y, B instead."""
    config = _config([("A", "a"), ("Y", "y"), ("X", "x"), ("B", "b")], [("A", "B"), ("X", "Y")])
    assert [f.label for f in sort_functionalities(config)] == ["A", "X", "B", "Y"]


def test_a_cycle_is_an_error_naming_the_functionalities_on_it() -> None:
    config = _config(
        [("F1", "source"), ("F2", "left"), ("F3", "right"), ("F4", "sink")],
        [("F1", "F2"), ("F2", "F3"), ("F3", "F2"), ("F3", "F4")],
    )
    with pytest.raises(CfgplanError) as caught:
        sort_functionalities(config)
    message = str(caught.value)
    assert "cycle" in message
    assert "F2: left(R)" in message and "F3: right(R)" in message
    assert "F1" not in message and "F4" not in message


def test_a_channel_from_nowhere_is_an_error() -> None:
    config = _config([("F1", "a")], [("F9", "F1")])
    with pytest.raises(CfgplanError, match="F9"):
        sort_functionalities(config)


@st.composite
def dags(draw: st.DrawFn) -> Configuration:
    n = draw(st.integers(1, 8))
    edges = draw(
        st.lists(
            st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)).filter(lambda e: e[0] < e[1]),
            max_size=12,
        )
    )
    listed = draw(st.permutations(range(n)))
    return _config([(f"F{i}", f"f{i}") for i in listed], [(f"F{a}", f"F{b}") for a, b in edges])


@given(dags())
def test_every_channel_goes_forward_in_the_sorted_order(config: Configuration) -> None:
    order = [f.label for f in sort_functionalities(config)]
    assert sorted(order) == sorted(f.label for f in config.functionalities)
    for ch in config.channels:
        assert order.index(ch.source) < order.index(ch.target)
