"""Bounding the rate of what a robot receives: a token bucket per sender and channel.

A robot's global channels hold one item (5.2.2): what it computes depends on
the newest value each channel brought since its last cycle. A robot that
floods a channel — a bug, or a robot of the society that was compromised —
would otherwise wake the receiver's loop at every message (a message wakes
it so that switches go through at once), make it read, trace and hand over
each one, and so starve it. So every message on a channel key (which names
the channel *and* its sender, :mod:`cfgplan.runtime.keys`) first passes a
token bucket of that key, on the Zenoh thread that delivers it, before
anything is read, stored or woken (:class:`Buckets`):

* the bucket refills at ``allowance`` times the rate the sender's period
  implies (a functionality of period 0.1 s sends 10 values a second; with
  the default allowance of 2, 20 a second are taken), at most ``ceiling``
  per second whatever period a message claims or when it claims none (a
  robot run with ``--rate 0``); until a first message was read (the period
  is the one its envelope states, :mod:`cfgplan.runtime.values`, at most
  60 s), ``ceiling`` holds;
* it holds ``burst`` messages, so that the jitter of the network, which
  bunches a sender's values, costs none of them — or, when more, as many as
  the sender's stated period makes in a *lease* (the seconds of silence the
  society rides out before a robot is lost, :class:`Buckets`), at most
  ``ceiling``: a receiver or a link that stalls for less than that, a frozen
  process let go, gets what was held back all at once, and that is no flood;
* a message that finds the bucket empty is dropped, unread, and counted;
  the receiver records the count per channel once per ``report_every``
  seconds (an ``error`` event naming the channel and its sender), never
  once per message.

Values that pass are handled exactly as before, so a flood changes what the
receiver computes by the values dropped and no more.

The switch protocol's messages (:mod:`cfgplan.runtime.protocol`) are bounded
the same way, per key — and each of them names one sender: the coordinator
hears each robot on a key of its own, a robot hears its switches on its
``configure`` key — by a bucket of ``control_burst`` messages refilled at
``control`` a second (200 and 200: a switch among many robots, a robot's
reports of a bad cycle, never come near it). What a flood of them costs is
recorded once per ``report_every`` seconds per sender; what passes and cannot
be read, or is not its sender's to say, is recorded once per kind, sender and
interval with a count of the others (:class:`Throttle`), so neither the
loop nor the trace grows with the flood. Settable through
:class:`RateLimits` (``ZenohOptions.rates``); pure Python, no clock of its own
(the caller passes the time), so it is tested without a network.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from cfgplan.run_errors import RunError

__all__ = ["Bucket", "Buckets", "RateLimits", "Throttle"]


@dataclass(frozen=True)
class RateLimits:
    """How many messages a robot takes per channel and sender (module docstring)."""

    allowance: float = 2.0
    """Messages taken per period of the sender (its period as its messages state it)."""
    burst: float = 8.0
    """Messages a bucket holds: that many may come at once."""
    ceiling: float = 200.0
    """The most messages per second taken on one channel, whatever period is stated."""
    report_every: float = 1.0
    """Seconds between two records of the messages dropped on one channel."""
    enabled: bool = True
    """False: every message is taken (measurements only)."""
    control: float = 200.0
    """The most switch-protocol messages per second taken from one sender."""
    control_burst: float = 200.0
    """Switch-protocol messages of one sender that may come at once."""

    def __post_init__(self) -> None:
        for name in ("allowance", "burst", "ceiling", "report_every", "control", "control_burst"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise RunError(f"rate limit {name} is {value!r}: a positive finite number")
        if self.burst < 1 or self.control_burst < 1:
            raise RunError("a rate limit's burst is at least one message")

    @property
    def for_control(self) -> RateLimits:
        """The limits of the switch protocol's keys: ``control`` a second,
        ``control_burst`` at once, whatever a message says."""
        return RateLimits(
            ceiling=self.control,
            burst=self.control_burst,
            report_every=self.report_every,
            enabled=self.enabled,
        )

    def rate(self, period: float | None) -> float:
        """Messages per second taken from a sender of ``period`` seconds (``None``: unknown)."""
        if period is None or not period > 0:
            return self.ceiling
        return min(self.ceiling, self.allowance / period)


@dataclass
class Bucket:
    """One channel's bucket: ``tokens`` left at time ``last``, refilled at ``rate``."""

    rate: float
    tokens: float
    last: float
    size: float
    """The most tokens it holds (:meth:`Buckets.size`)."""
    dropped: int = 0
    """Dropped since the last report."""
    total: int = 0
    """Dropped in all."""


@dataclass
class Buckets:
    """The buckets of a robot's channels, by channel key (not thread-safe:
    the transport holds its lock around every call)."""

    limits: RateLimits = field(default_factory=RateLimits)
    lease: float = 0.0
    """Seconds of silence the society rides out (the transport's lease): what a
    sender sends in that time may arrive at once after a stall."""
    _buckets: dict[str, Bucket] = field(default_factory=dict)
    _reported: float | None = None

    def size(self, period: float | None) -> float:
        """A bucket's size for a sender of ``period`` seconds: ``burst``, or
        the messages it sends in a lease, whichever is more, and never more
        than ``ceiling`` (a second's worth at the most that is taken); a
        sender that states no period gets ``burst``."""
        limits = self.limits
        if period is None or not period > 0:
            return limits.burst
        return max(limits.burst, min(self.lease / period, limits.ceiling))

    def open(self, key: str, now: float) -> None:
        """A channel on ``key`` is attached: a bucket of ``burst`` tokens at the
        ceiling's rate, until its sender states its period."""
        limits = self.limits
        bucket = Bucket(limits.rate(None), limits.burst, now, self.size(None))
        self._buckets.setdefault(key, bucket)

    def close(self, key: str) -> None:
        """The channel is detached (its drops not yet reported are forgotten)."""
        self._buckets.pop(key, None)

    def pace(self, key: str, period: float | None) -> None:
        """The sender on ``key`` states ``period``: its bucket refills at that pace."""
        bucket = self._buckets.get(key)
        if bucket is not None:
            bucket.rate = self.limits.rate(period)
            bucket.size = self.size(period)

    def admit(self, key: str, now: float) -> bool:
        """Whether a message on ``key`` is taken (a token spent) or dropped (counted).
        A key with no bucket (no channel attached) is not taken."""
        bucket = self._buckets.get(key)
        if bucket is None:
            return False
        if not self.limits.enabled:
            return True
        elapsed = max(0.0, now - bucket.last)
        bucket.tokens = min(bucket.size, bucket.tokens + elapsed * bucket.rate)
        bucket.last = now
        if bucket.tokens >= 1.0:
            bucket.tokens -= 1.0
            return True
        bucket.dropped += 1
        bucket.total += 1
        return False

    def due(self, now: float) -> list[tuple[str, int, float]]:
        """Once per ``report_every`` seconds: per key, the messages dropped since
        the last report and the rate taken (keys that dropped none are left out)."""
        if self._reported is not None and now - self._reported < self.limits.report_every:
            return []
        out = [(k, b.dropped, b.rate) for k, b in self._buckets.items() if b.dropped]
        if out:
            self._reported = now
            for bucket in self._buckets.values():
                bucket.dropped = 0
        return out

    @property
    def dropped(self) -> int:
        """Messages dropped in all, on the channels attached now."""
        return sum(b.total for b in self._buckets.values())


@dataclass
class Throttle:
    """What is said about dropped messages, at most once per ``every`` seconds
    for each key (a kind of message and its sender): the first of an interval
    is said, the others counted and said as a count when the interval is over
    (:meth:`due`). No clock of its own (the caller passes the time)."""

    every: float = 1.0
    _said: dict[str, float] = field(default_factory=dict)  # when each key was last said
    _counted: dict[str, int] = field(default_factory=dict)  # not said since
    most: int = 256
    """Keys kept at most (each a kind and a sender of the state: a few)."""

    def note(self, key: str, now: float) -> bool:
        """Whether to say this one now (else it is counted)."""
        last = self._said.get(key)
        if last is not None and now - last < self.every:
            self._counted[key] = self._counted.get(key, 0) + 1
            return False
        if last is None and len(self._said) >= self.most:
            return False
        self._said[key] = now
        return True

    def due(self, now: float) -> list[tuple[str, int]]:
        """Per key, the messages counted and not said, once its interval is over
        (then said: their count starts again)."""
        out = []
        for key, count in sorted(self._counted.items()):
            if now - self._said[key] >= self.every:
                out.append((key, count))
                self._said[key] = now
                del self._counted[key]
        return out
