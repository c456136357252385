"""Reading JSON another process wrote (cfgplan.runtime.wire): what the
protocol's readers take as an id, a number and a name."""

from __future__ import annotations

import json

import pytest

from cfgplan.runtime.wire import is_number, is_whole, name, names, whole


@pytest.mark.parametrize("text", ["true", "1.0", "1e999", '"1"', "null"])
def test_only_a_whole_json_number_is_whole(text: str) -> None:
    value = json.loads(text)
    assert not is_whole(value)
    with pytest.raises(ValueError, match="is not a configuration id"):
        whole(value, "a configuration id")
    assert whole(json.loads("7"), "a configuration id") == 7


def test_a_number_is_any_json_number_but_true() -> None:
    assert [is_number(json.loads(t)) for t in ("2", "2.5", "1e999", "true", '"2"')] == [
        True,
        True,
        True,
        False,
        False,
    ]


def test_names_are_strings_and_lists_of_strings() -> None:
    assert name("Emil") == "Emil" and names(["compass", "Emil"]) == ("compass", "Emil")
    for bad in (["compass", 1], "compass", [["Emil"]]):
        with pytest.raises(ValueError, match="is not a list of names"):
            names(bad)
    with pytest.raises(ValueError, match="is not a name"):
        name(["Pippi"])
