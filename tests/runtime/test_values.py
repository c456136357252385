"""The value rule of global channels (JSON) and the message envelope."""

from __future__ import annotations

import json
import math
from collections import OrderedDict
from enum import IntEnum

import pytest

from cfgplan.runtime import RunError
from cfgplan.runtime.values import (
    MAX_DEPTH,
    ValueRuleError,
    check,
    encode,
    envelope,
    jsonable,
    open_envelope,
    safe_repr,
)
from cfgplan.runtime.wire import loads


class Level(IntEnum):
    HIGH = 2


class Pose:
    def __repr__(self) -> str:
        return "Pose(1, 2)"


def test_what_travels_and_how_it_arrives() -> None:
    value = {"pos": (1.5, -2), "seen": [True, None, "Door1"], "level": Level.HIGH}
    assert json.loads(encode(value)) == {
        "pos": [1.5, -2],  # a tuple arrives as a list
        "seen": [True, None, "Door1"],
        "level": 2,  # a subclass as its base type
    }
    assert encode(OrderedDict(a=1)) == '{"a":1}'
    for number in (math.nan, math.inf, -math.inf):  # JSON has none of them: refused at the door
        with pytest.raises(ValueRuleError, match="not finite"):
            encode({"pos": [1.0, number]})


@pytest.mark.parametrize("constant", [b"NaN", b"Infinity", b"-Infinity"])
def test_a_message_with_a_nan_is_not_json_and_not_taken(constant: bytes) -> None:
    """Python's JSON reader takes NaN and Infinity, which are not JSON: a
    channel value holding one was taken and written to the trace as a bare
    NaN (a line no other JSON reader reads). It is refused as not JSON."""
    payload = b'{"from":"Pippi","seq":1,"t":1.0,"period":0.1,"value":[' + constant + b"]}"
    with pytest.raises(RunError, match="not JSON"):
        open_envelope(payload)
    assert loads(b"[1e999]") == [math.inf]  # a number too big is a number (checked where read)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (Pose(), "a value of type tests.runtime.test_values.Pose cannot travel as JSON"),
        ({"a": [1, {2}]}, "a value of type set at value['a'][1] cannot travel as JSON"),
        ({1: "x"}, "a dict key of type int cannot travel as JSON (keys must be str)"),
        (b"raw", "a value of type bytes cannot travel as JSON"),
    ],
)
def test_what_does_not_travel_is_named_with_its_type_and_place(value: object, message: str) -> None:
    with pytest.raises(ValueRuleError) as caught:
        encode(value)
    assert str(caught.value) == message
    assert caught.value.hint is not None and "JSON: None, bool" in caught.value.hint


def test_values_that_refer_to_themselves_or_nest_too_deep() -> None:
    loop: list[object] = [1]
    loop.append(loop)
    with pytest.raises(ValueRuleError, match=r"refers to itself at value\[1\]"):
        check(loop)
    shared = [1, 2]
    check([shared, shared, {"again": shared}])  # shared is not circular
    deep: list[object] = []
    cur = deep
    for _ in range(10_000):  # far past Python's recursion limit: no RecursionError
        nxt: list[object] = []
        cur.append(nxt)
        cur = nxt
    with pytest.raises(ValueRuleError, match=f"deeper than {MAX_DEPTH} levels"):
        check(deep)


def test_a_numpy_like_value_gets_a_conversion_hint() -> None:
    class Array:
        def tolist(self) -> list[int]:
            return [1]

    with pytest.raises(ValueRuleError, match=r"convert it with \.tolist\(\)"):
        check(Array())


def test_the_envelope_round_trip_and_what_is_refused() -> None:
    payload = envelope("Emil", 7, 1712.5, 0.1, encode((0.695, -2.601)))
    message = open_envelope(payload)
    assert message == ("Emil", 7, 1712.5, 0.1, [0.695, -2.601])
    assert open_envelope(envelope("Emil", 1, 2.0, None, "null")).period is None
    assert open_envelope(envelope("Emil", 1, 2.0, 60.0, "null")).period == 60.0  # once a minute
    for bad in (
        b"not json",
        b'{"from": "Emil"}',
        b'{"value": 1, "from": 3, "seq": 1, "t": 0}',
        b'{"value": 1, "from": "E", "seq": true, "t": 0}',
        b'{"value": 1, "from": "E", "seq": 1, "t": "now"}',
        b'{"value": 1, "from": "E", "seq": 1, "t": 0, "period": -1}',
        b'{"value": 1, "from": "E", "seq": 1, "t": 0, "period": 1e9}',  # detection off
        b'{"value": 1, "from": "E", "seq": 1, "t": 0, "period": 1e999}',
        b'{"value": 1, "from": "E", "seq": 1, "t": 1e999}',
        b"[" * 100_000,
    ):
        with pytest.raises(RunError):
            open_envelope(bad)


def test_the_trace_writes_what_is_not_json_by_type_and_repr() -> None:
    assert jsonable([1, "a"]) == [1, "a"]
    assert jsonable(Pose()) == {"$type": "tests.runtime.test_values.Pose", "$repr": "Pose(1, 2)"}
    loop: list[object] = [(1, 2)]
    loop.append({"me": loop, 3: "x"})
    assert jsonable(loop) == [
        [1, 2],
        {"$type": "dict", "$repr": "{'me': [(1, 2), {...}], 3: 'x'}"},
    ]
    inner: list[object] = ["a"]
    inner.append(inner)
    assert jsonable(inner) == ["a", {"$type": "list", "$repr": "..."}]


class Bad:
    def __repr__(self) -> str:
        raise ValueError("boom")


class Loops:
    def __repr__(self) -> str:
        return repr(self)


def test_safe_repr_blames_a_failing_repr_and_escapes_control_characters() -> None:
    text, problem = safe_repr(Bad())
    assert problem == "its __repr__ raised ValueError: boom"
    assert text == "<Bad object; its __repr__ raised ValueError: boom>"
    text, problem = safe_repr(Loops())
    assert problem is not None and problem.startswith("its __repr__ raised RecursionError")
    assert safe_repr("\x1b[31mred\x07")[0] == "'\\x1b[31mred\\x07'"
    assert safe_repr("x" * 1000, 20)[0] == "'" + "x" * 18 + "…"
