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
machine). A child process is forked at the search's first step — it shares the
grounding made so far — and *prepares* the solver on the second core (imports it,
grounds its program) while the search works, but solves nothing until the search's
budget is spent and the parent says *go*. A run that ends within the budget (the
thesis's instances, every small domain) has the child killed before it solves:
no race was run, and its output is the same to the byte, its work counts
included. Once raced, the child writes its answer back through a pipe, which the
search looks at as it checks the clock (:class:`Rival`, called
:func:`~cfgplan.planner.clock.beside` the search); the child's answer ends the
search by :class:`Overtaken`. A child that finds nothing (its relaxation is
looser than the thesis's planner here, or nothing is admissible, or time ran
out) leaves the search to go on alone; a search that ends first has the child
killed: either way the child is gone, by its pid, when the race is
(:func:`racing`). Which engine answered is the only thing that can differ from
one run to the next, and only in the run's statistics.

Only where a process can fork safely (:data:`FORKS`); elsewhere the search runs
alone.
"""

from __future__ import annotations

import gc
import os
import pickle
import select
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import NoReturn

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.report import Stats

Answer = tuple[Configuration | None, Stats]
"""A configuration (None: nothing is admissible, proven) and the work of the
engine that found it."""

Prepare = Callable[[], Callable[[], Answer | None]]
"""The solver as the child runs it: prepared at once, the answer (or None: it has
none) once the race starts."""

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
    """The solver's process beside a search: forked at the search's first step
    to prepare, told to go once the search has made :attr:`after` steps of the
    clock, looked at every :data:`POLL` steps from then on."""

    engine: Prepare
    after: int
    steps: int = 0
    pid: int | None = None
    """The child's, while it runs."""
    started: bool = False
    """Whether the child was told to go (the race was run, whoever won it)."""
    gave_up: bool = False
    """The child ended without an answer, or could not be forked: the search
    goes on alone."""
    status: int | None = None
    """How the child ended (:func:`os.waitpid`'s status), once it has."""
    _answers: int | None = None
    _go: int | None = None
    _in_child: bool = False

    def tick(self) -> None:
        """One step of the search's clock: fork, say go, or look for the answer."""
        if self._in_child or self.gave_up:
            return
        self.steps += 1
        if self.pid is None and not self.started:
            self._fork()
            if self.gave_up:
                return
        if not self.started:
            if self.steps >= self.after:
                self._start()
        elif self.steps % POLL == 0:
            self._look()

    def _fork(self) -> None:
        # A fork copies only the thread that forks: a lock another thread held
        # stays held in the child. The child touches little (the solver, two
        # pipes), and should it hang, the search never waits for it: it
        # answers alone, and the child is killed.
        ends: list[int] = []
        try:
            ends += os.pipe()
            ends += os.pipe()
            pid = os.fork()
        except OSError:  # no process or pipe to spare: the search runs alone
            for end in ends:
                os.close(end)
            self.gave_up = True
            return
        answers, answer, hear, go = ends
        if pid == 0:
            self._in_child = True
            os.close(answers)
            os.close(go)
            _answer(self.engine, hear, answer)
        os.close(answer)
        os.close(hear)
        self.pid, self._answers, self._go = pid, answers, go

    def _start(self) -> None:
        """Tell the child to solve."""
        assert self._go is not None
        self.started = True
        with suppress(BrokenPipeError):  # it died preparing: read as giving up
            os.write(self._go, b"!")

    def _look(self) -> None:
        """Raise :class:`Overtaken` if the child has answered; note that it gave up."""
        assert self._answers is not None
        ready, _, _ = select.select([self._answers], [], [], 0)
        if not ready:
            return
        chunks = []  # the child writes its answer whole, then exits: read to the end
        while chunk := os.read(self._answers, 1 << 16):
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
        for end in (self._answers, self._go):
            if end is not None:
                os.close(end)
        self._answers = self._go = None


def _answer(engine: Prepare, hear: int, answer: int) -> NoReturn:
    """The child: prepare ``engine``, wait for the word on ``hear``, then write
    its answer (pickled) to ``answer``; exit without returning into the search
    it was forked from, nor flushing what the parent had buffered (``os._exit``)."""
    code = 1
    try:
        _die_with(os.getppid())
        signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C: the parent reports
        gc.freeze()  # the parent's objects stay out of the child's collections (fewer copies)
        solve = engine()
        if os.read(hear, 1):  # the race starts (nothing: the parent has gone)
            found = solve()
            with os.fdopen(answer, "wb") as out:
                pickle.dump(found, out, protocol=pickle.HIGHEST_PROTOCOL)
            code = 0
    except BaseException:  # out of time, or no relaxation: the parent reads nothing
        pass
    finally:
        os._exit(code)


def _die_with(parent: int) -> None:
    """Have the kernel kill this process when ``parent`` ends, however it ends
    (``kill -9`` included: no ``finally`` of the parent's runs then), so that a
    child never outlives the search it races (Linux's PR_SET_PDEATHSIG; elsewhere
    the child ends when it next writes to the parent's closed pipe)."""
    if sys.platform != "linux":
        return
    import ctypes

    pr_set_pdeathsig = 1
    ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)
    if os.getppid() != parent:  # the parent ended before the request was made
        os._exit(1)


@contextmanager
def racing(engine: Prepare, after: int) -> Iterator[Rival]:
    """Run the block (a search) with the solver's process beside it
    (:class:`Rival`); the child is gone when the block is, however it ends."""
    rival = Rival(engine, after)
    try:
        with clock.beside(rival.tick):
            yield rival
    finally:
        rival.close()
