"""The channel of 5.2.2 and the in-process transport."""

from __future__ import annotations

import json

import pytest

from cfgplan.runtime import (
    ChannelKey,
    InProcessTransport,
    RunError,
    make_global_channel,
    make_local_channel,
)
from cfgplan.runtime.values import ValueRuleError


def test_one_slot_newer_data_overwrites_and_the_last_operation_is_kept() -> None:
    ch = make_local_channel("Emil", "F114", "F129", ("image", "Emil"))
    assert ch.data == ("image", "Emil") and ch.kind == "local"
    assert ch.last is None and not ch.fresh
    ch.write("first")
    ch.write("second")
    assert ch.last == "write" and ch.fresh
    assert ch.read() == "second"
    assert ch.last == "read" and not ch.fresh
    assert ch.read() == "second"  # the data stays; it is only no longer new


def test_reading_before_any_write_is_an_error() -> None:
    ch = make_local_channel("Emil", "F1", "F2", ("x",))
    with pytest.raises(RunError, match="before anything was written"):
        ch.read()


def test_a_global_channel_copies_writes_to_the_other_robot() -> None:
    """5.2.2: F116 on Pippi writes; the instance on Emil has the data for F118."""
    transport = InProcessTransport()
    data = ("global-orient", "Pippi")
    on_pippi = make_global_channel("Emil", "F116", "F118", data, robot="Pippi", transport=transport)
    on_emil = make_global_channel("Pippi", "F116", "F118", data, robot="Emil", transport=transport)
    on_pippi.write(1.25)
    assert on_emil.fresh and on_emil.read() == 1.25
    assert not on_emil.fresh
    assert on_pippi.fresh  # the writer's own end: nobody reads it there
    assert (transport.sent, transport.undelivered) == (1, 0)


def test_a_global_value_travels_as_json_in_process_too() -> None:
    """The value rule holds for every transport: a tuple arrives as a list,
    a value that cannot travel is refused before anything is written."""
    transport = InProcessTransport()
    data = ("pos", "Pippi", "Door1")
    on_emil = make_global_channel("Pippi", "F7", "F3", data, robot="Emil", transport=transport)
    on_pippi = make_global_channel("Emil", "F7", "F3", data, robot="Pippi", transport=transport)
    on_emil.write((0.5, {"x": [1, None]}), period=0.1)
    assert on_pippi.read() == [0.5, {"x": [1, None]}]
    assert on_pippi.period == 0.1  # the sender's period travels with the value
    with pytest.raises(ValueRuleError, match="type set at value\\[1\\]"):
        on_emil.write((1, {3}))
    assert not on_pippi.fresh and transport.sent == 1


def test_a_message_that_is_not_an_envelope_is_refused_clearly() -> None:
    transport = InProcessTransport()
    ch = make_global_channel("Emil", "F1", "F2", ("x",), robot="Pippi", transport=transport)
    for bad in (b"\xff", b"[1, 2]", json.dumps({"value": 1}).encode()):
        with pytest.raises(RunError, match="message"):
            ch.receive(bad)
    assert not ch.fresh


def test_a_message_naming_another_sender_than_the_channels_is_refused() -> None:
    """Found by a review on a keyed society: a process with Pippi's key put
    ``{"from": "Mallory", ...}`` on Pippi's channel to Emil; Emil took the value
    and traced it as received from Mallory. The channel's key names its
    sender, so an envelope that says otherwise is refused, value untouched."""
    transport = InProcessTransport()
    ch = make_global_channel("Emil", "F7", "F3", ("pos",), robot="Pippi", transport=transport)
    good = {"from": "Emil", "seq": 1, "t": 1.0, "period": 0.1, "value": [1.0, 2.0]}
    ch.receive(json.dumps(good).encode())
    assert ch.read() == [1.0, 2.0]
    for sender in ("Mallory", "Pippi", "\x1b[31mred"):
        forged = dict(good, value=[99.0, 99.0], **{"from": sender})
        with pytest.raises(RunError, match="says it is from") as info:
            ch.receive(json.dumps(forged).encode())
        assert "on the channel from Emil" in info.value.message
        assert "\x1b" not in info.value.message  # shown escaped, not sent to the terminal
    assert ch.peek() == [1.0, 2.0] and not ch.fresh


def test_a_value_for_a_robot_not_in_the_process_is_dropped_and_counted() -> None:
    transport = InProcessTransport()
    ch = make_global_channel("Pippi", "F1", "F2", ("x",), robot="Emil", transport=transport)
    ch.write(3)
    assert (transport.sent, transport.undelivered) == (1, 1)


def test_a_global_channel_with_both_ends_on_one_robot_stays_on_it() -> None:
    """5.1 keeps such a channel global for the cost (build-a-wall); at run
    time it is one end, written and read like a local channel."""
    transport = InProcessTransport()
    ch = make_global_channel("Emil", "F1", "F2", ("x",), robot="Emil", transport=transport)
    ch.write({1, 2})  # not JSON, and need not be: it never leaves Emil
    assert ch.read() == {1, 2} and transport.sent == 0


def test_the_same_channel_twice_on_one_robot_is_an_error() -> None:
    transport = InProcessTransport()
    make_global_channel("Pippi", "F1", "F2", ("x",), robot="Emil", transport=transport)
    with pytest.raises(RunError, match="twice on Emil"):
        make_global_channel("Pippi", "F1", "F2", ("x",), robot="Emil", transport=transport)


def test_staleness_is_judged_by_the_senders_period() -> None:
    ch = make_local_channel("Emil", "F1", "F2", ("x",))
    assert not ch.stale(100.0, 3)  # never written: waiting, not stale
    ch.write(1, period=0.5, now=10.0)
    assert not ch.stale(11.5, 3)  # exactly 3 periods
    assert ch.stale(11.6, 3)
    ch.read()
    assert ch.stale(11.6, 3)  # read or not, nothing new came
    ch.write(2, now=20.0)  # a sender without a period: never stale
    assert not ch.stale(1000.0, 3)
    assert ChannelKey("F1", "F2", ("x",)) == ch.key and str(ch.key) == "F1->F2 (x)"
