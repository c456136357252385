"""Dividing a sorted configuration per robot (5.1, 5.4).

A functionality runs on its robot (its first argument) and a local channel
lives on its robot; a global channel refers to two robots and each of them
gets one end of it. The result is one *individual configuration* per robot,
labelled with the robot's name, as the thesis shows them in 5.4::

    (configuration Pippi
      Functionalities:
        F3: cross-door(Pippi, Door1)
        F10: compass(Pippi)
      Channels:
        global(Pippi, Emil, F10, F12, global-orient(Pippi))
        ...)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from cfgplan.configuration.describe import channel_text
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.diagnostics import error

__all__ = ["Individual", "divide"]


@dataclass(frozen=True)
class Individual:
    """One robot's part of a configuration: its functionalities in sorted
    order and its channels in the configuration's channel order."""

    robot: str
    functionalities: tuple[FunctionalityInstance, ...]
    channels: tuple[Channel, ...]

    def text(self) -> str:
        """The individual configuration description of 5.4."""
        lines = [f"(configuration {self.robot}", "  Functionalities:"]
        lines += [f"    {f}" for f in self.functionalities]
        lines.append("  Channels:")
        lines += [f"    {channel_text(c)}" for c in self.channels]
        lines.append(")")
        return "\n".join(lines)


def robots_of(channel: Channel) -> tuple[str, ...]:
    """Where a channel lives: one robot for a local channel, both ends (once
    each) for a global one."""
    if channel.kind == "local":
        return (channel.source_robot,)
    if channel.source_robot == channel.target_robot:
        return (channel.source_robot,)
    return (channel.source_robot, channel.target_robot)


def divide(config: Configuration, order: Sequence[FunctionalityInstance]) -> tuple[Individual, ...]:
    """Split ``config`` per robot, functionalities in the sorted ``order``.

    Robots come in order of first appearance in the configuration's own
    functionality list (5.4 shows Pippi, then Emil), then any robot that only
    a channel names.
    """
    if sorted(f.label for f in order) != sorted(f.label for f in config.functionalities):
        raise error("divide: the sorted order does not hold the configuration's functionalities")
    robots = dict.fromkeys(config.agents)
    for ch in config.channels:
        robots.update(dict.fromkeys(r for r in robots_of(ch) if r not in robots))
    return tuple(
        Individual(
            robot,
            tuple(f for f in order if f.robot == robot),
            tuple(ch for ch in config.channels if robot in robots_of(ch)),
        )
        for robot in robots
    )
