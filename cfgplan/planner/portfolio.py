"""The search and the solver race for the cheapest configuration (thesis 4.5).

The best-first search (:mod:`cfgplan.planner.search`) and the solver's bracket
and walk (:mod:`cfgplan.planner.solver`) are both exact: they find the same
configuration, the first of the cheapest cost in the thesis's order, labels and
derivation number included (``tests/planner/test_solver.py`` checks it on random
domains). Their times do not follow each other: the search falls off cliffs
where its ties and bounds happen to fall badly (hierarchies whose siblings share
children, overlapping fusions), the solver where its relaxation is loose or its
walk long (conversion graphs, dags); ``python -m benchmarks.engines`` runs them
side by side. Which one is faster cannot be told from the input, so on a machine
with two cores both run, and the first to end answers.

The search runs alone first, for :attr:`~cfgplan.planner.options.SearchOptions.race`
steps of the clock (:func:`cfgplan.planner.clock.check`, the same count on every
machine): a run that ends within them (the thesis's instances, every small
domain) forks nothing, and its output is the same to the byte, its work counts
included. Then a child process is forked — it shares the grounding made so far —
and runs the solver; it writes its answer back through a pipe, which the search
looks at as it checks the clock (:class:`Rival`, called :func:`~cfgplan.planner.clock.beside`
the search). The child's answer ends the search by :class:`Overtaken`. A child that
finds nothing (its bracket did not close in the time left, or nothing is
admissible) leaves the search to go on alone, and one that ends first has the
child killed: either way the child is gone, by its pid, when the race is
(:func:`racing`). Which engine answered is the only thing that can differ from
one run to the next, and only in the run's statistics.

Only where a process can fork safely (:data:`FORKS`), and not from a process
that runs threads of its own (a fork copies only the thread that forks); elsewhere
the search runs alone.
"""

from __future__ import annotations

import gc
import os
import pickle
import select
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import NoReturn

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.report import Stats

Answer = tuple[Configuration, Stats]
"""A configuration and the work of the engine that found it."""

FORKS = hasattr(os, "fork") and sys.platform != "darwin"
"""Whether this platform forks a Python process safely (not macOS, whose
system frameworks may not survive a fork; not Windows, which has none)."""

POLL = 16
"""Clock steps between two looks at the pipe (a system call each, about 1 µs;
the search makes 5,000–25,000 steps a second)."""


class Overtaken(Exception):
    """The solver's process answered before the search: its configuration and its work."""

    def __init__(self, answer: Answer) -> None:
        super().__init__("the solver answered first")
        self.answer = answer


@dataclass
class Rival:
    """The solver's process beside a search: started once the search has made
    :attr:`after` steps of the clock, looked at every :data:`POLL` steps."""

    engine: Callable[[], Answer | None]
    """What the child runs: the solver's answer, or None (it has none)."""
    after: int
    steps: int = 0
    pid: int | None = None
    """The child's, while it runs."""
    started: bool = False
    """Whether the child was started (the race was run, whoever won it)."""
    gave_up: bool = False
    """The child ended without an answer: the search goes on alone."""
    status: int | None = None
    """How the child ended (:func:`os.waitpid`'s status), once it has."""
    _pipe: int | None = None
    _in_child: bool = False

    def tick(self) -> None:
        """One step of the search's clock: start the child, or look for its answer."""
        if self._in_child or self.gave_up:
            return
        self.steps += 1
        if not self.started:
            if self.steps >= self.after:
                self._start()
        elif self.steps % POLL == 0:
            self._look()

    def _start(self) -> None:
        if threading.active_count() > 1:  # a fork copies only this thread: not safe
            self.gave_up = True
            return
        self.started = True
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:
            self._in_child = True
            os.close(read)
            _answer(self.engine, write)
        os.close(write)
        self.pid, self._pipe = pid, read

    def _look(self) -> None:
        """Raise :class:`Overtaken` if the child has answered; note that it gave up."""
        assert self._pipe is not None
        ready, _, _ = select.select([self._pipe], [], [], 0)
        if not ready:
            return
        chunks = []  # the child writes its answer whole, then exits: read to the end
        while chunk := os.read(self._pipe, 1 << 16):
            chunks.append(chunk)
        self.close()
        # From this process's own fork, never from outside: pickle is safe here.
        answer: Answer | None = pickle.loads(b"".join(chunks)) if chunks else None
        if answer is None:
            self.gave_up = True
            return
        raise Overtaken(answer)

    def close(self) -> None:
        """Stop the child (if it still runs) and wait for it, by its pid."""
        if self.pid is not None:
            with suppress(ProcessLookupError):
                os.kill(self.pid, signal.SIGKILL)
            self.status = os.waitpid(self.pid, 0)[1]
            self.pid = None
        if self._pipe is not None:
            os.close(self._pipe)
            self._pipe = None


def _answer(engine: Callable[[], Answer | None], pipe: int) -> NoReturn:
    """The child: run ``engine`` and write its answer (pickled) to ``pipe``;
    exit without returning into the search it was forked from, nor flushing
    what the parent had buffered (``os._exit``)."""
    code = 1
    try:
        signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C: the parent reports
        gc.freeze()  # the parent's objects stay out of the child's collections (fewer copies)
        answer = engine()
        with os.fdopen(pipe, "wb") as out:
            pickle.dump(answer, out, protocol=pickle.HIGHEST_PROTOCOL)
        code = 0
    except BaseException:  # out of time, or no bracket: the parent reads nothing
        pass
    finally:
        os._exit(code)


@contextmanager
def racing(engine: Callable[[], Answer | None], after: int) -> Iterator[Rival]:
    """Run the block (a search) with the solver's process beside it
    (:class:`Rival`); the child is gone when the block is, however it ends."""
    rival = Rival(engine, after)
    try:
        with clock.beside(rival.tick):
            yield rival
    finally:
        rival.close()
