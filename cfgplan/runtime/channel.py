"""The channel of 5.2.2: one slot of data between two functionalities.

A channel keeps whether it is local or global, the other robot when it is
global, the type of its data (its descriptor, e.g. ``("image", "Emil")``), its
input and output functionalities, the data itself, and whether the last
operation was a read or a write. It holds one item: a write replaces what was
there, nothing is queued. A functionality sees new data because the last
operation was a write; reading sets it to read.

Local and global channels have one interface (:meth:`Channel.write`,
:meth:`Channel.read`, :attr:`Channel.fresh`). A global channel is created on
both robots; a write on one end also sends the value, as JSON in an envelope
(:mod:`cfgplan.runtime.values`), through a
:class:`~cfgplan.runtime.transport.Transport` to the other end, where it is
delivered as a write (:meth:`Channel.receive`). A global channel whose two
ends are on one robot (5.1 keeps it global for the cost) is one end there,
written and read like a local channel.

Beyond the thesis, a channel remembers when its data was last refreshed and
the period of the functionality that sent it, which is what staleness (3.2:
``Freq``) is judged by: :meth:`Channel.stale`. A received period also sets
how many messages per second the transport takes on the channel, if it
limits them (``pace``: :mod:`cfgplan.security.rates`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Literal

from cfgplan.runtime.errors import RunError, printable
from cfgplan.runtime.transport import ChannelKey, Transport
from cfgplan.runtime.values import Envelope, encode, envelope, open_envelope

__all__ = ["Channel", "Operation", "channel_id", "make_global_channel", "make_local_channel"]

Operation = Literal["read", "write"]


def channel_id(source: str, target: str, data: Sequence[str]) -> str:
    """The name both ends of a channel agree on: ``F10->F12 (global-orient Pippi)``."""
    return str(ChannelKey(source, target, tuple(data)))


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
        self.key = ChannelKey(source, target, tuple(data))
        if kind == "global" and (other is None or transport is None):
            raise RunError(f"global channel {self.key} needs the other robot and a transport")
        self.kind = kind
        self.robot = robot
        self.other = other
        self.last: Operation | None = None
        self.refreshed: float | None = None  # monotonic time of the last write or receipt
        self.period: float | None = None  # the sender's period when it wrote
        self.seq = 0  # writes sent from this end
        self.stale_reported = False
        self._value: object = None
        self._transport = transport

    @property
    def source(self) -> str:
        return self.key.source

    @property
    def target(self) -> str:
        return self.key.target

    @property
    def data(self) -> tuple[str, ...]:
        return self.key.data

    @property
    def id(self) -> str:
        return str(self.key)

    @property
    def remote(self) -> bool:
        """A global channel whose other end is on another robot."""
        return self.kind == "global" and self.other != self.robot

    @property
    def fresh(self) -> bool:
        """New data: the last operation was a write."""
        return self.last == "write"

    def write(
        self,
        value: object,
        *,
        period: float | None = None,
        now: float | None = None,
        encoded: str | None = None,
    ) -> None:
        """Replace the data; a global channel also sends it to the other robot.

        ``period`` is the writer's period (for staleness), ``encoded`` the
        value's JSON when the caller has it already. A value that cannot
        travel raises :class:`~cfgplan.runtime.values.ValueRuleError` before
        anything is written.
        """
        if self.remote and encoded is None:
            encoded = encode(value)
        self.deliver(value, period=period, now=now)
        if self.remote:
            assert self._transport is not None and self.other is not None and encoded is not None
            self.seq += 1
            message = envelope(self.robot, self.seq, time.time(), period, encoded)
            self._transport.send(self.key, self.other, message)

    def deliver(
        self, value: object, *, period: float | None = None, now: float | None = None
    ) -> None:
        """Data arrives at this end (from a local write or through the transport)."""
        self._value = value
        self.last = "write"
        self.period = period
        self.refreshed = time.monotonic() if now is None else now

    def receive(self, payload: bytes, now: float | None = None) -> Envelope:
        """A message from the other end: read its envelope and deliver the value.
        One whose envelope names another sender than the channel's other end
        is refused (:class:`RunError`), not taken under either name: the
        channel's key names its sender, and with ``--keys`` only that robot
        may put on it, so a false ``from`` is a robot lying in its message."""
        message = open_envelope(payload)
        if self.other is not None and message.sender != self.other:
            shown = printable(message.sender[:60])
            raise RunError(
                f"a message that says it is from {shown!r}, on the channel from {self.other}"
            )
        self.deliver(message.value, period=message.period, now=now)
        pace = getattr(self._transport, "pace", None)
        if pace is not None:  # the rate this channel takes follows its sender's period
            pace(self.key, message.period)
        return message

    def read(self) -> object:
        """The data; the last operation becomes a read."""
        if self.last is None:
            raise RunError(f"channel {self.id} on {self.robot} is read before anything was written")
        self.last = "read"
        return self._value

    def peek(self) -> object:
        """The data, leaving the last operation as it is."""
        return self._value

    def age(self, now: float) -> float | None:
        """Seconds since the data was last refreshed (``None``: never written)."""
        return None if self.refreshed is None else now - self.refreshed

    def stale(self, now: float, periods: float) -> bool:
        """Not refreshed for more than ``periods`` periods of its sender (3.2).
        Never written, or written by a sender without a period: not stale."""
        age = self.age(now)
        return age is not None and self.period is not None and age > periods * self.period

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
    if channel.remote:

        def receiver(payload: bytes) -> None:
            channel.receive(payload)

        transport.attach(robot, channel.key, receiver, other)
    return channel
