"""The channel of 5.2.2: one slot of data between two functionalities.

A channel keeps whether it is local or global, the other robot when it is
global, the type of its data (its descriptor, e.g. ``("image", "Emil")``), its
input and output functionalities, the data itself, and whether the last
operation was a read or a write. It holds one item: a write replaces what was
there, nothing is queued. A functionality sees new data because the last
operation was a write; reading sets it to read.

Local and global channels have one interface (:meth:`Channel.write`,
:meth:`Channel.read`, :attr:`Channel.fresh`). A global channel is created on
both robots; a write on one end also sends the value through a
:class:`~cfgplan.runtime.transport.Transport` to the other end, where it is
delivered as a write (:meth:`Channel.deliver`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from cfgplan.diagnostics import error
from cfgplan.runtime.transport import Transport

__all__ = ["Channel", "Operation", "channel_id", "make_global_channel", "make_local_channel"]

Operation = Literal["read", "write"]


def channel_id(source: str, target: str, data: Sequence[str]) -> str:
    """The name both ends of a channel agree on: ``F10->F12 (global-orient Pippi)``."""
    return f"{source}->{target} ({' '.join(data)})"


class Channel:
    """One channel end on ``robot`` (5.2.2)."""

    def __init__(
        self,
        kind: Literal["local", "global"],
        robot: str,
        source: str,
        target: str,
        data: Sequence[str],
        *,
        other: str | None = None,
        transport: Transport | None = None,
    ) -> None:
        if kind == "global" and (other is None or transport is None):
            raise error(f"global channel {channel_id(source, target, data)} needs a transport")
        self.kind = kind
        self.robot = robot
        self.other = other
        self.source = source
        self.target = target
        self.data = tuple(data)
        self.last: Operation | None = None
        self._value: object = None
        self._transport = transport

    @property
    def id(self) -> str:
        return channel_id(self.source, self.target, self.data)

    @property
    def fresh(self) -> bool:
        """New data: the last operation was a write."""
        return self.last == "write"

    def write(self, value: object) -> None:
        """Replace the data; a global channel also sends it to the other robot."""
        self.deliver(value)
        if self.kind == "global":
            assert self._transport is not None and self.other is not None
            self._transport.send(self.id, self.other, value)

    def deliver(self, value: object) -> None:
        """Data arrives at this end (from a local write or through the transport)."""
        self._value = value
        self.last = "write"

    def read(self) -> object:
        """The data; the last operation becomes a read."""
        if self.last is None:
            raise error(f"channel {self.id} on {self.robot} is read before anything was written")
        self.last = "read"
        return self._value

    def __repr__(self) -> str:
        where = self.robot if self.kind == "local" else f"{self.robot}<->{self.other}"
        return f"<{self.kind} channel {self.id} on {where}, last {self.last or 'none'}>"


def make_local_channel(robot: str, source: str, target: str, data: Sequence[str]) -> Channel:
    """``(make-local-channel 'Emil 'F114 'F129 '(image Emil))`` (5.2.2)."""
    return Channel("local", robot, source, target, data)


def make_global_channel(
    other: str,
    source: str,
    target: str,
    data: Sequence[str],
    *,
    robot: str,
    transport: Transport,
) -> Channel:
    """``(make-global-channel 'PIPPI 'F116 'F118 '(GLOBAL-ORIENT PIPPI))`` made on
    ``robot``: the end there, attached to ``transport`` to receive."""
    channel = Channel("global", robot, source, target, data, other=other, transport=transport)
    transport.attach(robot, channel.id, channel.deliver)
    return channel
