"""How a global channel's data reaches the other robot (5.2.2).

In the thesis a write on a global channel "copies the data to the instance at
[the other robot] through a socket connection". A :class:`Transport` is that
connection, reduced to what a channel needs: the receiving end *attaches*
itself under the channel's id, the writing end *sends* a value to a robot.

:class:`InProcessTransport` connects robots that run in one process (``cfgplan
run``, the emitted ``run_all.py``): a send is delivered at once. A value sent to
a robot that is not in the process is dropped and counted, nothing more; a
networked transport (sockets between robots) is not written yet.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from cfgplan.diagnostics import error

__all__ = ["InProcessTransport", "Receiver", "Transport"]

Receiver = Callable[[object], None]
"""What the receiving end of a channel does with a value that arrives."""


class Transport(Protocol):
    """The connection global channels write through."""

    def attach(self, robot: str, channel_id: str, receiver: Receiver) -> None:
        """Deliver values sent to ``channel_id`` on ``robot`` to ``receiver``."""

    def send(self, channel_id: str, robot: str, value: object) -> None:
        """Send ``value`` to the end of ``channel_id`` that lives on ``robot``."""


class InProcessTransport:
    """All robots in one process: :meth:`send` delivers synchronously."""

    def __init__(self) -> None:
        self._receivers: dict[tuple[str, str], Receiver] = {}
        self.sent = 0
        self.undelivered = 0

    def attach(self, robot: str, channel_id: str, receiver: Receiver) -> None:
        key = (robot, channel_id)
        if key in self._receivers:
            raise error(f"channel {channel_id} is created twice on {robot}")
        self._receivers[key] = receiver

    def send(self, channel_id: str, robot: str, value: object) -> None:
        self.sent += 1
        self.deliver(channel_id, robot, value)

    def deliver(self, channel_id: str, robot: str, value: object) -> None:
        """Hand ``value`` to the end attached on ``robot``; drop it if there is none."""
        receiver = self._receivers.get((robot, channel_id))
        if receiver is None:
            self.undelivered += 1
            return
        receiver(value)
