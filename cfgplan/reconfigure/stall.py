"""A coordinator that stood still: its own stall is not its helpers' loss (5.5).

When the coordinator's whole process stops (SIGSTOP, a hung machine), its Zenoh
session stops with it; when it runs again, the leases of the robots it watches
have run out *in its own session*, and it sees them lost though they never
stopped. Taken as they come, those losses withdraw a helper's facts, and the
society may find nothing admissible, only to take the helper back a moment
later, with a failure on record that never was.

* :class:`Heartbeat` — a thread that wakes every :data:`BEAT` seconds and keeps
  the longest pause it saw. It tells a stall of the whole process (the thread
  stood still too) from a loop pass that is only slow (a long search, a slow
  functionality: the thread and the session ran on, so a loss seen then is
  real).
* :class:`Doubts` — after such a stall (half the lease or more: a session
  woken from a stall of about the lease may drop a link whose keep-alives
  wait unread), each loss seen within two leases is
  held until its own deadline (two leases after it was held): let go if the
  robot is seen again by the same process, taken if the robot is still gone,
  or came back as another process, at the deadline. A robot that lost its own
  link to its router (:meth:`Doubts.cut_off`) holds the losses it sees the
  same way, for as long as the cut lasts and two leases more.

:class:`cfgplan.reconfigure.network.NetworkAdaptive` uses both.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from cfgplan.runtime.monitor import Detection

__all__ = ["BEAT", "Doubts", "Heartbeat"]

BEAT = 0.1
"""Seconds between two beats of a :class:`Heartbeat`."""


class Heartbeat:
    """A thread that notes how long the process stood still: :meth:`take` is
    the longest pause between two of its beats since the last :meth:`take`."""

    def __init__(self, beat: float = BEAT) -> None:
        self.beat = beat
        self._worst = 0.0
        self._last = time.monotonic()  # the last beat
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Beat from now on (a daemon thread, ended by :meth:`stop`)."""
        self._thread = threading.Thread(target=self._run, name="cfgplan-heartbeat", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        with self._lock:
            self._last = time.monotonic()
        while not self._stop.wait(self.beat):
            now = time.monotonic()
            with self._lock:
                pause, self._last = now - self._last - self.beat, now
            self.note(pause)

    def note(self, pause: float) -> None:
        """A pause of ``pause`` seconds beyond a beat (the thread calls it; tests too)."""
        with self._lock:
            self._worst = max(self._worst, pause)

    def take(self, now: float | None = None) -> float:
        """The longest pause since the last call, and start over. A pause
        still going on counts too: woken from a stall, the loop may ask before
        this thread has beaten again (and it sees the losses the stall made
        first), so the time since the last beat is part of the answer."""
        now = time.monotonic() if now is None else now
        with self._lock:
            worst, self._worst = self._worst, 0.0
            if self._thread is not None:
                worst = max(worst, now - self._last - self.beat)
        return worst

    def stop(self) -> None:
        """Stop beating: from now on :meth:`take` counts only the pauses noted
        (no beat is due, so the time since the last one is no pause)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        with self._lock:
            self._thread = None


@dataclass
class Doubts:
    """The losses held after the coordinator's own stall (module docstring)."""

    lease: float
    """Seconds of silence after which a robot is lost (the session's lease)."""
    share: float = 0.5
    """The part of the lease a stall of the process must last to put the
    losses seen after it in doubt: a session that stood still for less than
    the lease but more than this may still drop a link when it runs again
    (the keep-alives that arrived meanwhile wait unread behind its lease
    check), so a stall of *about* the lease is one too."""
    until: float = 0.0
    """Monotonic time before which a loss seen is held."""
    held: dict[str, tuple[Detection, float]] = field(default_factory=dict)
    """By robot: the loss held and its deadline (monotonic)."""

    @property
    def threshold(self) -> float:
        """Seconds a stall must last to count (:attr:`share` of the lease)."""
        return self.share * self.lease

    def stalled(self, now: float) -> None:
        """The process stood still longer than :attr:`threshold`: losses seen
        in the next two leases are held."""
        self.until = now + 2 * self.lease

    def cut_off(self, now: float) -> None:
        """This robot is cut off from the others (its own link to its router
        is gone): as after a stall, and every loss held waits at least two
        leases more. Nothing can be decided of a robot that cannot be heard;
        once the link is back, a robot still not seen two leases later is
        taken as lost."""
        self.stalled(now)
        for robot, (detection, deadline) in self.held.items():
            self.held[robot] = (detection, max(deadline, now + 2 * self.lease))

    def hold(self, detection: Detection, now: float) -> bool:
        """Whether ``detection``, a loss, is held (seen while in doubt)."""
        if detection.kind != "lost" or now >= self.until:
            return False
        self.held.setdefault(detection.other, (detection, now + 2 * self.lease))
        return True

    def seen(self, robot: str) -> Detection | None:
        """``robot`` is seen again: its held loss, if any, let go of (the
        caller takes it if the robot came back as another process)."""
        held = self.held.pop(robot, None)
        return held[0] if held is not None else None

    def due(self, now: float) -> list[Detection]:
        """The losses whose deadline passed, let go of (the caller takes those
        of robots still gone)."""
        out = [lost for lost, deadline in self.held.values() if now >= deadline]
        for lost in out:
            del self.held[lost.other]
        return out
