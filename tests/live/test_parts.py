"""The live page's address, drawing and fallbacks (cfgplan.live.address, diagram, watch)."""

from __future__ import annotations

import re
import time

import pytest

from cfgplan.live.address import Address, parse_address
from cfgplan.live.diagram import drawing
from cfgplan.live.model import Setup, input_key
from cfgplan.live.watch import Watch, fallback_rows
from cfgplan.notation import call_text
from cfgplan.reconfigure.fallbacks import resources
from cfgplan.reconfigure.policy import Reconfigurator
from tests.backends.support import cross_door_44


@pytest.mark.parametrize(
    ("text", "address"),
    [
        ("8080", Address("127.0.0.1", 8080)),
        ("0", Address("127.0.0.1", 0)),
        ("0.0.0.0:8080", Address("0.0.0.0", 8080)),
        ("[::1]:9", Address("::1", 9)),
        ("robot.local:80", Address("robot.local", 80)),
    ],
)
def test_addresses_default_to_the_loopback(text: str, address: Address) -> None:
    """[HOST:]PORT: the host is 127.0.0.1 unless given."""
    assert parse_address(text) == address


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("http", "a port is a whole number"),
        ("70000", "a port is a whole number"),
        (":80", "expected [HOST:]PORT"),
        ("::1:80", "write an IPv6 host in brackets"),
        ("[::1]80", "expected [HOST]:PORT"),
    ],
)
def test_bad_addresses_say_what_is_wrong(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        parse_address(text)


def test_the_url_of_a_wildcard_address_is_the_loopback() -> None:
    """A page open to the network is printed with an address this machine can open."""
    assert Address("0.0.0.0", 0).url(4321) == "http://127.0.0.1:4321/"
    assert Address("::1", 80).url() == "http://[::1]:80/"


def test_every_channel_and_functionality_of_the_drawing_is_tagged() -> None:
    """The SVG names the input each channel feeds and the resource each box is,
    so the page colours them without a layout of its own."""
    problem, config = cross_door_44()
    source, svg = drawing(config, problem.goal_call[1:])
    assert source.startswith("digraph")
    assert svg is not None and svg.startswith("<svg")
    for ch in config.channels:
        assert f'data-input="{input_key(ch.target, ch.data)}"' in svg
    for f in config.functionalities:
        assert f'data-resource="{call_text(f.key)}"' in svg
    for robot in config.agents:
        assert f'class="cluster" data-robot="{robot}"' in svg
    assert "<script" not in svg


def test_the_fallbacks_are_read_from_the_reconfigurator() -> None:
    """One row per resource; once computed, the compass's fallback is the
    camera configuration, 47 (6.2.2 step 3)."""
    problem, config = cross_door_44()
    r = Reconfigurator(problem.task, problem.domain, problem.goal_call, config)
    rows = fallback_rows(r)
    assert [row["resource"] for row in rows] == [
        x.text for x in resources(config, problem.task.media)
    ]
    assert not any(row["known"] for row in rows)
    while r.prepare():
        pass
    compass = next(row for row in fallback_rows(r) if row["resource"] == "compass(Emil)")
    assert compass["known"] and compass["cost"] == 47
    assert "compass(Emil)" in compass["stopped"]


def test_the_drawing_is_laid_out_again_only_when_the_configuration_changes() -> None:
    """A switch (a new running configuration) gives a new drawing number."""
    problem, config = cross_door_44()
    r = Reconfigurator(problem.task, problem.domain, problem.goal_call, config)
    setup = Setup("t", ("Emil", "Pippi"), ("Emil", "Pippi"), "Emil", 44, time.time())
    watch = Watch(setup, config, problem.goal_call[1:], r)
    first = watch.drawing()
    assert watch.drawing() is first and watch.state()["drawing"] == first[0] == 1
    r.running = None
    assert watch.state()["drawing"] == 0 and watch.drawing()[2] is None
