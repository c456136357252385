"""Finding a key of a scenario file again, for messages with a caret."""

from __future__ import annotations

from cfgplan.sim.locate import locate

TEXT = """name = "x"
world.bar.length = 1.2

[world]
rooms = { Room1 = [0, 0, 3, 3], Room2 = [0, 3, 3, 6] }

[world.doors.Door1]
at = [1.5, 3.0]

[robots.Pippi]
at = [1, 1, 0]
params = { carry = { route = [[1, 0]] } }

[[events]]
at = 1.0

[[events]]
at = 2.0
break = "laser(Emil)"
"""


def where(*path: str | int) -> tuple[int, int] | None:
    span = locate(TEXT, "s.toml", path)
    return None if span is None else (span.line, span.column)


def test_keys_in_tables_inline_tables_and_arrays_of_tables() -> None:
    assert where("name") == (1, 1)
    assert where("world", "bar", "length") == (2, 1)  # a dotted key
    assert where("world", "rooms", "Room2") == (5, 33)  # inside an inline table
    assert where("world", "doors", "Door1", "at") == (8, 1)
    assert where("world", "doors", "Door1") == (7, 14)  # the table's header
    assert where("robots", "Pippi", "at", 2) == (11, 1)  # an element: its key
    assert where("robots", "Pippi", "params", "carry", "route") == (12, 22)
    assert where("events", 1, "break") == (19, 1)  # the second [[events]]
    assert where("events", 0, "at") == (15, 1)


def test_what_is_not_written_points_at_the_nearest_enclosing_key() -> None:
    assert where("robots", "Pippi", "camera", "fov") == (10, 9)  # [robots.Pippi]
    assert where("nothing") is None
