"""How a global channel's data reaches the other robot (5.2.2).

In the thesis a write on a global channel "copies the data to the instance at
[the other robot] through a socket connection". A :class:`Transport` is that
connection, reduced to what a robot needs:

* the receiving end of a channel *attaches* a receiver under the channel's
  :class:`ChannelKey`; the writing end *sends* the encoded message (an
  envelope, :mod:`cfgplan.runtime.values`) to the robot at the other end;
* :meth:`Transport.poll` hands over what arrived, on the robot's own thread,
  once per pass of its loop — the newest message per channel only (the one
  slot of 5.2.2);
* :meth:`Transport.watch` reports the robots it exchanges data with as they
  appear and disappear; :meth:`Transport.close` ends the connection.

:class:`InProcessTransport` joins robots that run in one process (``cfgplan
run``, the emitted ``run_all.py``): a send is delivered at once; a message for
a robot that is not in the process is dropped and counted. Robots of one
process live and stop together, so it reports no presence.
:class:`~cfgplan.runtime.zenoh_transport.ZenohTransport` joins robots across
processes and hosts.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import NamedTuple, Protocol

from cfgplan.notation import atom_text
from cfgplan.runtime.errors import RunError

__all__ = ["ChannelKey", "InProcessTransport", "Presence", "Receiver", "Transport"]


class ChannelKey(NamedTuple):
    """What both ends of a channel agree on: its source and target
    functionalities and its data, e.g. ``F10->F12 (global-orient Pippi)``."""

    source: str
    target: str
    data: tuple[str, ...]

    def __str__(self) -> str:
        return f"{self.source}->{self.target} {atom_text(self.data)}"


Receiver = Callable[[bytes], None]
"""What the receiving end of a channel does with a message that arrives."""

Presence = Callable[[str, bool], None]
"""Told ``(robot, True)`` when a robot appears, ``(robot, False)`` when it is lost."""


class Transport(Protocol):
    """The connection global channels write through."""

    def attach(self, robot: str, key: ChannelKey, receiver: Receiver, sender: str) -> None:
        """Deliver messages ``sender`` sends to channel ``key`` on ``robot`` to
        ``receiver`` (those of any other robot are not)."""

    def detach(self, robot: str, key: ChannelKey) -> None:
        """Stop delivering channel ``key`` on ``robot`` (the channel was stopped)."""

    def send(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        """Send ``payload`` to the end of channel ``key`` that lives on ``robot``."""

    def watch(self, robot: str, partners: Collection[str], report: Presence) -> None:
        """Tell ``report`` (at :meth:`poll`) when one of ``partners`` appears or is lost."""

    def poll(self) -> None:
        """Hand over what arrived since the last poll: the newest message per
        channel to its receiver, appearances and losses to their watchers."""

    def close(self) -> None:
        """End the connection (other robots see this robot leave)."""


class InProcessTransport:
    """All robots in one process: :meth:`send` delivers synchronously.

    Robots of one process live and stop together, except when one is killed
    on purpose (fault injection, :meth:`leave`): then the robots watching it
    are told it is lost, and what is sent to it is dropped (not counted as
    undelivered); :meth:`join` brings it back.
    """

    def __init__(self) -> None:
        self._receivers: dict[tuple[str, ChannelKey], Receiver] = {}
        self._watchers: dict[str, tuple[frozenset[str], Presence]] = {}
        self.gone: set[str] = set()
        self.presence_listeners: list[Presence] = []
        """Told of every robot killed or back, partner or not (the coordinator)."""
        self.sent = 0
        self.undelivered = 0

    def attach(self, robot: str, key: ChannelKey, receiver: Receiver, sender: str) -> None:
        """Robots of one process cannot pass for one another: ``sender`` is not checked."""
        if (robot, key) in self._receivers:
            raise RunError(f"channel {key} is created twice on {robot}")
        self._receivers[(robot, key)] = receiver

    def detach(self, robot: str, key: ChannelKey) -> None:
        self._receivers.pop((robot, key), None)

    def send(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        self.sent += 1
        self.deliver(key, robot, payload)

    def deliver(self, key: ChannelKey, robot: str, payload: bytes) -> None:
        """Hand ``payload`` to the end attached on ``robot``; drop it if there is none."""
        if robot in self.gone:
            return
        receiver = self._receivers.get((robot, key))
        if receiver is None:
            self.undelivered += 1
            return
        receiver(payload)

    def watch(self, robot: str, partners: Collection[str], report: Presence) -> None:
        """Tell ``report`` when one of ``partners`` is killed or comes back
        (robots of one process otherwise come and go together)."""
        self._watchers[robot] = (frozenset(partners), report)
        for other in sorted(set(partners) & self.gone):
            report(other, False)

    def leave(self, robot: str) -> None:
        """``robot`` is gone: its watchers see it lost."""
        self.gone.add(robot)
        self._tell(robot, False)

    def join(self, robot: str) -> None:
        """``robot`` is back: its watchers see it again."""
        self.gone.discard(robot)
        self._tell(robot, True)

    def _tell(self, robot: str, alive: bool) -> None:
        for watcher, (partners, report) in list(self._watchers.items()):
            if robot in partners and watcher not in self.gone:
                report(robot, alive)
        for listener in self.presence_listeners:
            listener(robot, alive)

    def poll(self) -> None:
        """Nothing waits: every send was delivered at once."""

    def close(self) -> None:
        """Nothing to close."""
