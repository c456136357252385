"""Reading a scenario file: TOML parsed, then checked, every problem at its place.

A TOML syntax error is reported with the line and column :mod:`tomllib`
gives; a value of the wrong kind or a misspelt key with the place of its key
(:mod:`cfgplan.sim.locate`), as pydantic's validation of
:class:`~cfgplan.sim.scenario.Scenario` finds them; then what the types
cannot say — boxes the right way round, robots standing in a room, the
robots a bar, a block or ``expect`` names, the sensors world changes break.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from pydantic import ValidationError

from cfgplan.diagnostics import CfgplanError, Diagnostic, error
from cfgplan.sim.locate import locate, span_at
from cfgplan.sim.scenario import Loaded, Scenario, room_of, sensor_problem

__all__ = ["read_scenario"]


_AT = re.compile(r"\(at line (\d+), column (\d+)\)")


def read_scenario(file: str, text: str, folder: Path) -> Loaded:
    """Parse and validate a scenario; :class:`CfgplanError` with every problem."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        found = _AT.search(message)
        span = span_at(file, int(found.group(1)), int(found.group(2))) if found else None
        raise error(f"not a scenario (TOML): {_AT.sub('', message).strip()}", span) from None
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as exc:
        raise CfgplanError(_validation(exc, file, text)) from None
    loaded = Loaded(scenario, file, text, folder)
    problems = _geometry(loaded)
    if problems:
        raise CfgplanError(problems)
    return loaded


def _validation(exc: ValidationError, file: str, text: str) -> list[Diagnostic]:
    out: list[Diagnostic] = []
    for item in exc.errors():
        path = [p for p in item["loc"] if isinstance(p, str | int)]
        # pydantic names the member of a union or the alias it tried: keep the keys
        keys = [p for p in path if not (isinstance(p, str) and p in _UNION_PARTS)]
        shown = ".".join(str(p) if isinstance(p, str) else f"[{p}]" for p in keys)
        shown = shown.replace(".[", "[")
        if item["type"] == "extra_forbidden":
            message = f"{shown}: unknown key"
            hint = "see docs/reference/scenario-file.md for the keys of a scenario"
        elif item["type"] == "missing" and keys and isinstance(keys[-1], int):
            base = shown.rsplit("[", 1)[0]
            message = f"{base}: too few values (expected at least {keys[-1] + 1})"
            hint = None
        elif item["type"] == "missing":
            message = f"{shown}: missing"
            hint = None
        else:
            message = f"{shown}: {item['msg'].lower()}"
            hint = None
        out.append(Diagnostic("error", message, locate(text, file, keys), hint))
    return out


_UNION_PARTS = {"float", "int", "str", "list[str]", "bool"}


def _geometry(loaded: Loaded) -> list[Diagnostic]:
    """What the types cannot say: boxes the right way round, sizes positive,
    robots standing in a room and clear of walls, references that exist."""
    s = loaded.scenario
    out: list[Diagnostic] = []
    for name, box in s.world.rooms.items():
        if not (box[2] > box[0] and box[3] > box[1]):
            out.append(
                loaded.problem(
                    f"world.rooms.{name}: expected [x0, y0, x1, y1] with x1 > x0 and y1 > y0",
                    "world",
                    "rooms",
                    name,
                )
            )
    sized = [("blocks", n, b.size) for n, b in s.world.blocks.items()]
    sized += [("walls", n, w.size) for n, w in s.world.walls.items()]
    for kind, name, size in sized:
        if min(size) <= 0:
            out.append(
                loaded.problem(
                    f"world.{kind}.{name}.size: both sides must be more than 0",
                    "world",
                    kind,
                    name,
                    "size",
                )
            )
    robots = set(s.robots)
    if s.world.bar is not None:
        for who in s.world.bar.robots:
            if who not in robots:
                out.append(_unknown_robot(loaded, who, "world", "bar", "robots"))
    for name, block in s.world.blocks.items():
        for side, who in block.pushers.items():
            if who not in robots:
                out.append(_unknown_robot(loaded, who, "world", "blocks", name, "pushers", side))
        if block.target is not None and block.target not in s.world.walls:
            out.append(
                loaded.problem(
                    f"world.blocks.{name}.target: no wall {block.target} in world.walls",
                    "world",
                    "blocks",
                    name,
                    "target",
                )
            )
    for who, room in s.expect.rooms.items():
        if who not in robots:
            out.append(_unknown_robot(loaded, who, "expect", "rooms", who))
        if room not in s.world.rooms:
            out.append(
                loaded.problem(
                    f"expect.rooms.{who}: no room {room} in world.rooms", "expect", "rooms", who
                )
            )
    pushers = {who for b in s.world.blocks.values() for who in b.pushers.values()}
    for name, spec in s.robots.items():
        if name in pushers:
            continue  # placed against its block
        if spec.at is None:
            out.append(loaded.problem(f"robots.{name}.at: missing (x, y, heading)", "robots", name))
            continue
        x, y, _ = spec.at
        if room_of(s.world.rooms, x, y) is None:
            out.append(
                loaded.problem(
                    f"robots.{name}.at: ({x:g}, {y:g}) is in no room of world.rooms",
                    "robots",
                    name,
                    "at",
                )
            )
    for i, event in enumerate(s.events):
        given = [e for e in (event.breaks, event.repair, event.magnetic) if e is not None]
        if len(given) != 1:
            out.append(
                loaded.problem(
                    f"events[{i}]: give exactly one of break, repair, magnetic", "events", i, "at"
                )
            )
        for key, target in (("break", event.breaks), ("repair", event.repair)):
            if target is not None:
                problem = sensor_problem(target, robots)
                if problem:
                    out.append(loaded.problem(f"events[{i}].{key}: {problem}", "events", i, key))
    return out


def _unknown_robot(loaded: Loaded, who: str, *path: str) -> Diagnostic:
    known = ", ".join(sorted(loaded.scenario.robots)) or "none"
    return loaded.problem(f"{'.'.join(path)}: no robot {who} in robots (robots: {known})", *path)
