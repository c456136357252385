"""The channel of 5.2.2 and the in-process transport."""

from __future__ import annotations

import pytest

from cfgplan.diagnostics import CfgplanError
from cfgplan.runtime import InProcessTransport, make_global_channel, make_local_channel


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
    with pytest.raises(CfgplanError, match="before anything was written"):
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


def test_a_value_for_a_robot_not_in_the_process_is_dropped_and_counted() -> None:
    transport = InProcessTransport()
    ch = make_global_channel("Pippi", "F1", "F2", ("x",), robot="Emil", transport=transport)
    ch.write(3)
    assert (transport.sent, transport.undelivered) == (1, 1)


def test_the_same_channel_twice_on_one_robot_is_an_error() -> None:
    transport = InProcessTransport()
    make_global_channel("Pippi", "F1", "F2", ("x",), robot="Emil", transport=transport)
    with pytest.raises(CfgplanError, match="twice on Emil"):
        make_global_channel("Pippi", "F1", "F2", ("x",), robot="Emil", transport=transport)
