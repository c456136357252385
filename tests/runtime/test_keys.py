"""Where a society's data lives on Zenoh: the documented key layout."""

from __future__ import annotations

import pytest

from cfgplan.runtime import ChannelKey
from cfgplan.runtime.keys import (
    alive_key,
    alive_pattern,
    channel_key,
    chunk,
    configure_key,
    coordinator_key,
    process_key,
    process_of_token,
    robot_of_alive,
    unchunk,
)


def test_the_key_of_a_global_channel_reads_society_robot_channel() -> None:
    key = ChannelKey("F7", "F3", ("pos", "Pippi", "Door1"))
    assert (
        channel_key("lab", "Pippi", key, "Emil")
        == "cfgplan/lab/Pippi/ch/Emil/F7/F3/pos/Pippi/Door1"
    )
    assert alive_key("lab", "Emil") == "cfgplan/lab/Emil/alive"
    assert alive_pattern("lab") == "cfgplan/lab/*/alive"
    assert configure_key("lab", "Pippi") == "cfgplan/lab/Pippi/configure"
    assert coordinator_key("lab", "Pippi") == "cfgplan/lab/coordinator/Pippi"  # from Pippi


@pytest.mark.parametrize(
    ("name", "chunked"),
    [
        ("cross-door", "cross-door"),
        ("a/b", "a%2Fb"),
        ("*", "%2A"),
        ("$*", "%24%2A"),
        ("#?", "%23%3F"),
        ("@ros", "%40ros"),
        ("100%", "100%25"),
        ("Émil", "%C3%89mil"),
        ("two words", "two%20words"),
        ("", "%"),
    ],
)
def test_chunks_never_carry_zenoh_syntax_and_come_back(name: str, chunked: str) -> None:
    assert chunk(name) == chunked
    assert unchunk(chunked) == name


def test_a_robot_is_read_back_from_its_token_only_in_its_society() -> None:
    assert robot_of_alive(alive_key("lab", "Ro/bot*"), "lab") == "Ro/bot*"
    assert robot_of_alive(alive_key("lab", "Emil"), "other") is None
    assert robot_of_alive("cfgplan/lab/Emil/ch/F1", "lab") is None


def test_a_token_whose_name_is_no_utf8_names_no_robot() -> None:
    """A foreign token under the society's prefix (``%FF``) is not ours: no
    UnicodeDecodeError in the liveliness callback of every robot."""
    assert robot_of_alive("cfgplan/lab/%FF/alive", "lab") is None


def test_a_process_token_names_its_robot_and_instance() -> None:
    """Each process of a robot declares one (the coordinator tells a second
    process apart by it); read back as the alive and problem tokens are."""
    key = process_key("lab", "Ro/bot*", "0f3a")
    assert key == "cfgplan/lab/Ro%2Fbot%2A/process/0f3a"
    assert process_of_token(key, "lab") == ("Ro/bot*", "0f3a")
    assert process_of_token(key, "other") is None
    assert process_of_token(alive_key("lab", "Emil"), "lab") is None
    assert process_of_token(key + "/more", "lab") is None
    assert process_of_token("cfgplan/lab/%FF/process/x", "lab") is None
