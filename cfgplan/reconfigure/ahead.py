"""Fallbacks computed ahead of time on a thread of their own (5.5, 7.2).

After each switch the coordinator wants, for every resource the running
configuration uses, the configuration to run if that resource fails, so that
a failure is answered without searching. On the thesis's domains each takes
a millisecond or two; on a large society a search on a freshly derived task
(whose grounding is new) may take a good part of a second, and an answer of
"none" is followed by the search that explains it. Done on the robots'
thread this would delay their cycles, so an :class:`Ahead` computes them in
the background, one after the other, each given :data:`AHEAD_LIMIT` seconds
(a search cut by it keeps nothing: that resource's failure is then planned
for when it happens). Each fallback is planned on a task of its own, derived
for the purpose, so the robots' thread never plans a task this thread is
planning. A new decision restarts the list. Once the running
configuration's fallbacks are known, the situations a recovery of what is
out would return to are planned, and their fallbacks too where the society
would stay on its configuration
(:meth:`~cfgplan.reconfigure.policy.Reconfigurator.look_ahead`): a recovery
that switches nothing then finds them ready.
"""

from __future__ import annotations

import threading

from cfgplan.reconfigure.policy import Reconfigurator

__all__ = ["AHEAD_LIMIT", "Ahead"]

AHEAD_LIMIT = 2.0
"""Seconds one fallback's search may take in the background."""


class Ahead:
    """A daemon thread that computes the running configuration's fallbacks."""

    def __init__(self, reconfigurator: Reconfigurator, time_limit: float = AHEAD_LIMIT) -> None:
        self.reconfigurator = reconfigurator
        self.time_limit = time_limit
        self._wake = threading.Event()
        self._closed = False
        self.idle = threading.Event()
        """Set while there is nothing left to compute (for tests and benchmarks)."""
        self._thread = threading.Thread(target=self._run, name="cfgplan fallbacks", daemon=True)
        self._thread.start()
        self.notify()

    def notify(self) -> None:
        """The running configuration or the situation changed: (re)start the list."""
        self.idle.clear()
        self._wake.set()

    def close(self) -> None:
        """End the thread: at once when idle, else after the search it is in."""
        self._closed = True
        self._wake.set()

    def _run(self) -> None:
        while not self._closed:
            self._wake.wait()
            self._wake.clear()
            while not self._closed:
                job = self.reconfigurator.next_fallback()
                if job is not None:
                    self.reconfigurator.compute(*job, time_limit=self.time_limit)
                elif not self.reconfigurator.look_ahead(self.time_limit):
                    break
            if not self._wake.is_set():
                self.idle.set()
