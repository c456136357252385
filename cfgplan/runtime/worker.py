"""A thread per functionality, so that a call that blocks does not freeze its robot.

The thesis's configuration calls each wrapper in turn (5.3, the LAMBDA). A
call that never returns would stop the whole robot; so each functionality's
actual function runs on a thread of its own (a daemon: it never keeps the
process alive) and the robot waits for it at most the per-call *time
budget*. A call over budget is reported once; the functionality is *busy*
until that call returns — its later calls are skipped and its outputs go
stale — and what the late call returns is discarded, since its inputs are
old by then. With no budget (``None``) the function runs on the robot's own
thread, as in the thesis.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Literal

__all__ = ["Outcome", "Worker"]

Outcome = tuple[Literal["done", "raised", "overran"], object]


def _stop() -> object:
    return None


_STOP = _stop  # the job that ends a worker's thread
"""``("done", result)``, ``("raised", exception)`` or ``("overran", None)``."""


class Worker:
    """Runs one functionality's calls with a time budget."""

    def __init__(self, name: str, prepare: Callable[[], None] = lambda: None) -> None:
        self.name = name
        self._prepare = prepare  # run once on the thread (e.g. set current_robot)
        self._jobs: queue.SimpleQueue[Callable[[], object]] = queue.SimpleQueue()
        self._done = threading.Event()
        self._outcome: Outcome = ("done", None)
        self._thread: threading.Thread | None = None
        self._busy = False

    @property
    def busy(self) -> bool:
        """A call that overran its budget is still running."""
        return self._busy and not self._done.is_set()

    def run(self, job: Callable[[], object], budget: float) -> Outcome:
        """``job()`` on the worker thread, waiting at most ``budget`` seconds."""
        if self.busy:
            raise RuntimeError(f"{self.name}: a call is still running")
        if self._thread is None:
            self._thread = threading.Thread(target=self._serve, name=self.name, daemon=True)
            self._thread.start()
        self._done.clear()
        self._busy = True
        self._jobs.put(job)
        if not self._done.wait(budget):
            return ("overran", None)
        self._busy = False
        return self._outcome

    def close(self) -> None:
        """End the thread once it is idle (a call still running finishes first)."""
        if self._thread is not None:
            self._jobs.put(_STOP)
            self._thread = None

    def _serve(self) -> None:
        self._prepare()
        while True:
            job = self._jobs.get()
            if job is _STOP:
                return
            try:
                self._outcome = ("done", job())
            except BaseException as exc:  # SystemExit too: reported, never raised here
                self._outcome = ("raised", exc)
            self._done.set()
