"""The wrapper of 5.2.1: run only on fresh input and a true precondition; beyond
the thesis, frequencies (3.2), staleness, faults kept with their functionality
and a per-call time budget."""

from __future__ import annotations

import sys
import threading

import pytest

from cfgplan.runtime import (
    Call,
    Event,
    Implementation,
    InProcessTransport,
    Staleness,
    Wrapper,
    current_robot,
    make_global_channel,
    make_local_channel,
)
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


class Clock:
    """A clock the test moves by hand."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _ch(name: str) -> Channel:
    return make_local_channel("Emil", "F1", "F2", (name, "Emil"))


def _called(event: Call | None) -> Call:
    assert event is not None
    return event


def test_runs_only_when_every_input_is_fresh() -> None:
    spy = Spy(result=("p", "o"))
    wrapper = Wrapper("Emil", "F9", "measure-door", ("Door1",), Implementation("m", spy))
    image, other = _ch("image"), _ch("other")
    pos, orient_a, orient_b = _ch("pos"), _ch("orient"), _ch("orient")
    image.write("img")
    event = _called(wrapper([image, other], [[pos], [orient_a, orient_b]]))
    assert spy.calls == [] and event.status == "waiting"
    assert event.waiting == (("other", "Emil"),)
    assert image.fresh  # a waiting wrapper reads nothing
    other.write("x")
    event = _called(wrapper([image, other], [[pos], [orient_a, orient_b]]))
    assert spy.calls == [("Door1", "img", "x")] and spy.robots == ["Emil"]
    assert event.status == "ran" and not image.fresh and not other.fresh
    # each output goes to all of its channels
    assert (pos.read(), orient_a.read(), orient_b.read()) == ("p", "o", "o")
    # nothing new: no second run
    assert _called(wrapper([image, other], [[pos], [orient_a, orient_b]])).status == "waiting"
    assert len(spy.calls) == 1


def test_a_false_precondition_keeps_the_function_from_running() -> None:
    spy = Spy(result=1.0)
    allowed = {"now": False}
    impl = Implementation(
        "compass", spy, precondition=lambda: allowed["now"] and current_robot() == "Pippi"
    )
    wrapper = Wrapper("Pippi", "F10", "compass", (), impl)
    out = _ch("global-orient")
    assert _called(wrapper([], [[out]])).status == "precondition"
    assert spy.calls == [] and not out.fresh
    allowed["now"] = True
    assert _called(wrapper([], [[out]])).status == "ran" and out.read() == 1.0


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
    assert _called(wrapper([None], [])).status == "waiting" and spy.calls == []


def test_the_wrong_number_of_outputs_is_the_functionalitys_error() -> None:
    wrapper = Wrapper("Emil", "F9", "measure-door", ("Door1",), Implementation("m", Spy(1.0)))
    pos, orient = _ch("pos"), _ch("orient")
    event = _called(wrapper([], [[pos], [orient]]))
    assert event.status == "error" and "must return 2 outputs" in event.error
    assert not pos.fresh and not orient.fresh


def test_a_failing_implementation_is_reported_and_nothing_is_written() -> None:
    def broken(image: object) -> None:
        raise ZeroDivisionError("no")

    wrapper = Wrapper("Emil", "F8", "camera", (), Implementation("camera", broken))
    image, out = _ch("image"), _ch("pos")
    image.write("img")
    event = _called(wrapper([image], [[out]]))
    assert event.status == "error"
    assert event.error.startswith("the implementation raised ZeroDivisionError: no (")
    assert "test_wrapper.py:" in event.error and "in broken)" in event.error
    assert not image.fresh  # it saw the input: the same data is not tried again
    assert not out.fresh  # its output goes stale
    assert (
        wrapper.stats.by_status == {"error": 1} and "ZeroDivisionError" in wrapper.stats.last_error
    )


@pytest.mark.parametrize("budget", [None, 5.0])
def test_sys_exit_inside_an_implementation_is_reported(budget: float | None) -> None:
    def leaves() -> None:
        sys.exit(3)

    wrapper = Wrapper("Emil", "F8", "camera", (), Implementation("camera", leaves))
    wrapper.schedule(0, 0.0, budget)
    event = _called(wrapper([], [[_ch("image")]]))
    assert event.status == "error" and event.error == "the implementation called sys.exit(3)"


def test_a_blocking_call_is_detected_and_skipped_until_it_returns() -> None:
    release = threading.Event()
    runs: list[int] = []

    def blocks() -> int:
        runs.append(1)
        if len(runs) == 1:
            release.wait(30)  # bounded, released by the test
        return len(runs)

    wrapper = Wrapper("Emil", "F8", "camera", (), Implementation("camera", blocks))
    wrapper.schedule(0, 0.0, budget=0.2)
    out = _ch("image")
    event = _called(wrapper([], [[out]]))
    assert event.status == "timeout" and "time budget of 0.2 s" in event.error
    assert _called(wrapper([], [[out]])).status == "busy" and len(runs) == 1
    release.set()
    for _ in range(300):  # the late call returns; then the functionality runs again
        event = _called(wrapper([], [[out]]))
        if event.status == "ran":
            break
        threading.Event().wait(0.01)
    assert event.status == "ran" and out.read() == 2  # the late result was discarded


def test_an_output_for_another_robot_that_cannot_travel_is_the_functionalitys_error() -> None:
    transport = InProcessTransport()
    remote = make_global_channel(
        "Pippi", "F8", "F3", ("image", "Emil"), robot="Emil", transport=transport
    )
    local = _ch("image")
    wrapper = Wrapper("Emil", "F8", "camera", (), Implementation("camera", Spy(object())))
    event = _called(wrapper([], [[local, remote]]))
    assert event.status == "error"
    assert "output image(Emil) goes to another robot, but a value of type object" in event.error
    assert not local.fresh and transport.sent == 0  # nothing written at all


def test_frequencies_a_functionality_runs_at_its_freq_others_at_the_rate() -> None:
    """3.2: Freq. At rate 10, a :freq 20 functionality runs twice as often."""
    clock = Clock()
    fast = Wrapper("Emil", "F1", "fast", (), Implementation("fast", Spy(1)), freq=20, clock=clock)
    slow = Wrapper("Emil", "F2", "slow", (), Implementation("slow", Spy(1)), clock=clock)
    for w in (fast, slow):
        w.schedule(10, 0.0)
    ran = {"fast": 0, "slow": 0}
    for tick in range(20):  # one second in steps of 50 ms
        clock.now = tick * 0.05
        for w in (fast, slow):
            if w([], [[_ch("x")]]) is not None:
                ran[w.name] += 1
    assert ran == {"fast": 20, "slow": 10}
    slow.schedule(0, 0.0)  # rate 0: every call, :freq or not
    assert all(slow([], [[_ch("x")]]) is not None for _ in range(3))


def test_stale_input_is_refused_and_said_so() -> None:
    """An input not refreshed for 3 periods of its sender is stale (3.2)."""
    clock = Clock()
    events: list[Event] = []

    def record(e: Event) -> Event:
        events.append(e)
        return e

    spy = Spy()
    wrapper = Wrapper(
        "Pippi", "F3", "cross-door", ("Door1",), Implementation("c", spy), record, clock=clock
    )
    wrapper.schedule(10, 0.0)
    pos = make_local_channel("Pippi", "F7", "F3", ("pos", "Pippi", "Door1"))
    pos.write((1.0, 2.0), period=0.1, now=0.0)
    assert _called(wrapper([pos], [])).status == "ran"
    pos.write((1.0, 2.0), period=0.1, now=0.05)
    clock.now = 0.4  # 0.35 s after the last write: more than 3 x 0.1 s
    event = _called(wrapper([pos], []))
    assert event.status == "stale" and event.stale == (("pos", "Pippi", "Door1"),)
    assert len(spy.calls) == 1 and pos.fresh  # not run, not consumed
    (went,) = [e for e in events if isinstance(e, Staleness)]
    assert (went.state, went.label, went.period) == ("stale", "F3", 0.1)
    assert went.age == pytest.approx(0.35) and went.limit == pytest.approx(0.3)
    clock.now = 0.5
    assert _called(wrapper([pos], [])).status == "stale"  # still; reported once
    pos.write((1.0, 2.5), period=0.1, now=0.55)
    clock.now = 0.6
    assert _called(wrapper([pos], [])).status == "ran"
    assert [e.state for e in events if isinstance(e, Staleness)] == ["stale", "fresh"]
    assert wrapper.stats.by_status == {"ran": 2, "stale": 2}
