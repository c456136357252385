"""The wrapper of 5.2.1: run only on fresh input and a true precondition."""

from __future__ import annotations

import pytest

from cfgplan.diagnostics import CfgplanError
from cfgplan.runtime import Implementation, Wrapper, current_robot, make_local_channel
from cfgplan.runtime.channel import Channel


class Spy:
    """An actual function that records its calls."""

    def __init__(self, result: object = None) -> None:
        self.calls: list[tuple[object, ...]] = []
        self.robots: list[str] = []
        self.result = result

    def __call__(self, *args: object) -> object:
        self.calls.append(args)
        self.robots.append(current_robot())
        return self.result


def _ch(name: str) -> Channel:
    return make_local_channel("Emil", "F1", "F2", (name, "Emil"))


def test_runs_only_when_every_input_is_fresh() -> None:
    spy = Spy(result=("p", "o"))
    wrapper = Wrapper("Emil", "F9", "measure-door", ("Door1",), Implementation("m", spy))
    image, other = _ch("image"), _ch("other")
    pos, orient_a, orient_b = _ch("pos"), _ch("orient"), _ch("orient")
    image.write("img")
    event = wrapper([image, other], [[pos], [orient_a, orient_b]])
    assert spy.calls == [] and event.status == "waiting"
    assert event.waiting == (("other", "Emil"),)
    assert image.fresh  # a waiting wrapper reads nothing
    other.write("x")
    event = wrapper([image, other], [[pos], [orient_a, orient_b]])
    assert spy.calls == [("Door1", "img", "x")] and spy.robots == ["Emil"]
    assert event.status == "ran" and not image.fresh and not other.fresh
    # each output goes to all of its channels
    assert (pos.read(), orient_a.read(), orient_b.read()) == ("p", "o", "o")
    # nothing new: no second run
    assert wrapper([image, other], [[pos], [orient_a, orient_b]]).status == "waiting"
    assert len(spy.calls) == 1


def test_a_false_precondition_keeps_the_function_from_running() -> None:
    spy = Spy(result=1.0)
    allowed = {"now": False}
    impl = Implementation(
        "compass", spy, precondition=lambda: allowed["now"] and current_robot() == "Pippi"
    )
    wrapper = Wrapper("Pippi", "F10", "compass", (), impl)
    out = _ch("global-orient")
    assert wrapper([], [[out]]).status == "precondition"
    assert spy.calls == [] and not out.fresh
    allowed["now"] = True
    assert wrapper([], [[out]]).status == "ran" and out.read() == 1.0


def test_none_means_no_data_for_that_output() -> None:
    spy = Spy(result=(None, 2))
    wrapper = Wrapper("Emil", "F1", "f", (), Implementation("f", spy))
    a, b = _ch("a"), _ch("b")
    wrapper([], [[a], [b]])
    assert not a.fresh and b.fresh


def test_several_channels_into_one_input_the_first_fresh_one_counts() -> None:
    spy = Spy()
    wrapper = Wrapper("Emil", "F1", "act", (), Implementation("act", spy))
    first, second = _ch("x"), _ch("x")
    second.write("from second")
    wrapper([[first, second]], [])
    first.write("from first")
    second.write("again")
    wrapper([[first, second]], [])
    assert spy.calls == [("from second",), ("from first",)]
    assert not first.fresh and not second.fresh


def test_an_input_without_channel_never_has_data() -> None:
    spy = Spy()
    wrapper = Wrapper("Emil", "F1", "act", (), Implementation("act", spy))
    assert wrapper([None], []).status == "waiting" and spy.calls == []


def test_the_wrong_number_of_outputs_is_a_clear_error() -> None:
    wrapper = Wrapper("Emil", "F9", "measure-door", ("Door1",), Implementation("m", Spy(1.0)))
    with pytest.raises(CfgplanError, match="must return 2 outputs"):
        wrapper([], [[_ch("pos")], [_ch("orient")]])


def test_a_failing_implementation_is_named() -> None:
    def broken() -> None:
        raise ZeroDivisionError("no")

    wrapper = Wrapper("Emil", "F8", "camera", (), Implementation("camera", broken))
    with pytest.raises(CfgplanError, match=r"F8: camera\(Emil\) on Emil.*ZeroDivisionError"):
        wrapper([], [[_ch("image")]])
