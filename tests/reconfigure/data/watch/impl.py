"""Implementations of the watch domain (a test of the takeover): the camera
sees the door open, and the log counts what it is told."""

from __future__ import annotations

from cfgplan.runtime import functionality


@functionality("camera")
def camera() -> dict[str, bool]:
    return {"Door1": True}


@functionality("detect")
def detect(door: str, image: dict[str, bool]) -> bool:
    return bool(image.get(door))


@functionality("keep-log")
def keep_log(door: str, state: bool) -> None:
    """Nothing to do: the call itself, with its input, is the goal's data."""
