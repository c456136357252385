"""The answer-set solver over the graph of ground instances, and its race with
the search (thesis 4.5).

The cheapest configuration's cost, bracketed by an answer-set solver (thesis 4.5).

The planner of 4.5 expands every *occurrence* of a method instance on its own,
so an exact model of it needs a copy of an instance per occurrence (Fibonacci-many
on a hierarchy whose levels share their children). Two models over the graph of
ground instances (:mod:`cfgplan.planner.graph`), one copy per instance, bracket it
instead (``configure.lp`` beside this module holds both):

- **one expansion per instance** (``exact``): every occurrence of an instance is
  expanded the same way, and no instance lies below itself. Each of its models is
  a derivation of 4.5, so its optimum is an *upper* bound, and its optimal model a
  configuration the depth-first planner also derives;
- **the relaxation** (``relaxed``): an instance may be expanded several ways, and
  a channel needs only one of the ways its ends can be re-wired. Every
  derivation of 4.5 is one of its models, so its optimum is a *lower* bound.

Where the two meet, that is the cost of the cheapest configuration
(:attr:`Bracket.exact`), proven without enumerating derivations; where they do
not, the cheapest lies between them. Costs are counted in the unit every weight
and ``:cost`` is a multiple of (:mod:`cfgplan.planner.costs`); a task whose
costs have no unit (a reliability weight adds logarithms) has no bracket.

The facts written for the solver (what ``configure.lp`` reads):

- ``goal(G)``; ``method(M)``; ``opt(M,O)``, O the expansion's number among the
  method's choices (:attr:`cfgplan.planner.graph.Option.choice`);
  ``body(M,O,I,Y)``: body item I is instance Y;
- ``spec(M,O,S,K,Ra,Rb,Is,It,D,B)``: the option's channel S, of kind K
  (``local``/``global``, an ``any`` channel resolved), declared on robots Ra, Rb,
  from item Is to item It, with data D and bandwidth B (-1: none);
- ``outp(M,O,D,I,B)``, ``inp(M,O,D,I)``: the option's ``:out`` and ``:in`` entries;
- ``func(F)``; ``fbind(F,B)``, B the binding's number (state order);
  ``fout(F,B,D)``, ``fin(F,B,D)``; ``robot(F,R)``, F's first argument; ``fcost(F,C)``;
- ``agentw(R,W)``, ``chw(K,W)``, ``medium(N,Ra,Rb,Cap)`` and ``media`` when the
  state declares media (4.6).

Instances, data and robots are written as numbers (the order they are met in),
costs in units, bandwidths in the unit of the bandwidths and capacities.

The search and the solver race for the cheapest configuration (thesis 4.5).

The best-first search (:mod:`cfgplan.planner.search`) and the solver's bracket
and walk are both exact: they find the same
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
import math
import os
import pickle
import select
import signal
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from fractions import Fraction
from importlib import resources
from typing import TYPE_CHECKING, NoReturn

from cfgplan.configuration.model import Configuration
from cfgplan.planner import clock
from cfgplan.planner.costs import unit_of
from cfgplan.planner.graph import Graph, graph_of
from cfgplan.planner.ground import Grounder
from cfgplan.planner.grow import Grower, successors
from cfgplan.planner.partial import Partial, root
from cfgplan.planner.report import DeadEnd, Stats
from cfgplan.planner.task import Ground, Task

if TYPE_CHECKING:
    import clingo


Choices = Mapping[Ground, int]
"""Per method instance the number of its expansion (:attr:`Option.choice`), per
functionality instance the number of its binding."""


@dataclass(frozen=True, slots=True)
class Model:
    """The cheapest answer a solver run found: its cost and what it chose."""

    cost: float
    choices: Choices


@dataclass(frozen=True, slots=True)
class Bracket:
    """Where the cheapest configuration's cost lies: ``lower`` <= it <= ``upper``.

    ``lower`` is what the relaxation proved (its optimum, or the bound it reached
    within the time given); math.inf when it has no model: nothing is
    admissible. ``upper`` is the cheapest one-expansion-per-instance answer
    found, a configuration of that cost (None: none found)."""

    lower: float
    upper: Model | None

    @property
    def exact(self) -> bool:
        """Whether the bracket is closed: the cheapest cost is known (and is
        ``upper.cost``), or it is known that nothing is admissible."""
        if self.upper is None:
            return self.lower == math.inf
        return self.upper.cost <= self.lower


class Unsupported(Exception):
    """The task has no unit its costs (or bandwidths) are multiples of."""


class Inadmissible(Exception):
    """The relaxation has no model: no configuration is admissible (proven)."""


@dataclass
class _Facts:
    """The facts of one task and goal, and the names behind their numbers."""

    lines: list[str]
    calls: dict[Ground, int]
    names: dict[int, Ground]
    methods: set[int]
    unit: Fraction
    """The unit costs are counted in (:attr:`cfgplan.planner.task.Task.levels`)."""


def _units(values: list[float], unit: Fraction) -> list[int]:
    out = []
    for v in values:
        q = Fraction(repr(float(v))) / unit
        if q.denominator != 1:
            raise Unsupported(f"{v} is not a whole multiple of {unit}")
        out.append(int(q))
    return out


def _facts(task: Task, graph: Graph, goal: Ground) -> _Facts:
    """The facts of ``goal``'s instances, walked from the goal over the graph."""
    cost_unit = task.levels.unit
    if cost_unit is None:
        raise Unsupported("costs have no unit (a reliability weight adds logarithms)")
    capacities = [m.capacity for m in task.media]
    calls: dict[Ground, int] = {}
    data: dict[Ground, int] = {}
    agents: dict[str, int] = {}
    lines: list[str] = []
    methods: set[int] = set()
    widthed: list[tuple[str, str, float | None]] = []  # facts waiting for the bandwidth unit

    def number(call: Ground) -> int:
        found = calls.get(call)
        if found is None:
            found = calls[call] = len(calls)
            todo.append(call)
        return found

    def datum(d: Ground) -> int:
        return data.setdefault(d, len(data))

    def agent(a: str) -> int:
        return agents.setdefault(a, len(agents))

    todo: list[Ground] = []
    lines.append(f"goal({number(goal)}).")
    while todo:
        call = todo.pop()
        n = calls[call]
        instance = graph.instance(call)
        if instance.functionality:
            schema = task.functionality(call)
            assert schema is not None
            lines.append(f"func({n}). robot({n},{agent(call[1])}).")
            (cost,) = _units([task.costs.functionality(schema, call)], cost_unit)
            lines.append(f"fcost({n},{cost}).")
            for b, inst in enumerate(graph.grounder.instances(schema, call)):
                ins, outs = inst.io
                lines.append(f"fbind({n},{b}).")
                lines.extend(f"fin({n},{b},{datum(d)})." for d in dict.fromkeys(ins))
                lines.extend(f"fout({n},{b},{datum(d)})." for d in dict.fromkeys(outs))
            continue
        methods.add(n)
        lines.append(f"method({n}).")
        for option in instance.options:
            o, e = option.choice, option.expansion
            lines.append(f"opt({n},{o}).")
            lines.extend(f"body({n},{o},{i},{number(y)})." for i, y in enumerate(e.body))
            for s, (kind, robots, src, dst, d, bw) in enumerate(e.channels):
                ra, rb = agent(robots[0]), agent(robots[-1])
                args = f"{n},{o},{s},{kind},{ra},{rb},{src},{dst},{datum(d)}"
                widthed.append(("spec", args, bw))
            for d, (i, port) in e.outputs.items():
                widthed.append(("outp", f"{n},{o},{datum(d)},{i}", port))
            for d, offsets in e.inputs.items():
                lines.extend(f"inp({n},{o},{datum(d)},{i})." for i in offsets)
    bandwidths = [w for _, _, w in widthed if w is not None]
    width_unit = unit_of([*bandwidths, *capacities]) if task.media else Fraction(1)
    if width_unit is None:
        raise Unsupported("bandwidths have no unit")
    for predicate, args, width in widthed:
        # Bandwidths matter only where the state declares media (4.6).
        units = -1 if width is None or not task.media else _units([width], width_unit)[0]
        lines.append(f"{predicate}({args},{units}).")
    g, loc = _units([task.costs.channel("global"), task.costs.channel("local")], cost_unit)
    lines.append(f"chw(global,{g}). chw(local,{loc}).")
    for a, k in agents.items():
        (aw,) = _units([task.costs.agent(a)], cost_unit)
        lines.append(f"agentw({k},{aw}).")
    if task.media:
        lines.append("media.")
        for i, m in enumerate(task.media):
            if m.sender in agents and m.receiver in agents:
                cap = _units([m.capacity], width_unit)[0]
                lines.append(f"medium({i},{agents[m.sender]},{agents[m.receiver]},{cap}).")
    return _Facts(lines, calls, {v: k for k, v in calls.items()}, methods, cost_unit)


def _grounded(facts: _Facts, program: str, mode: str) -> clingo.Control:
    """The encoding and ``facts`` grounded with ``program`` (``exact`` or
    ``relaxed``), for clasp's optimisation ``mode``, core-guided (``usc``): it
    proves lower bounds as it goes, and on shapes with long plateaus of equal
    cost ends where branch and bound does not."""
    import clingo  # imported here: only a run that asks for the solver loads it

    control = clingo.Control([f"--opt-mode={mode}", "--opt-strategy=usc", "--warn=none"])
    control.add("base", [], resources.files(__package__).joinpath("configure.lp").read_text())
    control.add("base", [], "\n".join(facts.lines))
    control.ground([("base", []), (program, [])])
    return control


@dataclass(frozen=True, slots=True)
class _Run:
    """What one solver run found: its cheapest model (None: none), the bound it
    proved (math.inf: no model at all), and whether it ended (the bound is then
    the optimum, or the program has no model)."""

    best: Model | None
    bound: float
    ended: bool


def _optimum(facts: _Facts, program: str, seconds: float | None) -> _Run:
    """Optimise ``program`` (``exact`` or ``relaxed``) over ``facts`` for at most
    ``seconds`` (None: to the end)."""
    control = _grounded(facts, program, "opt")
    found: list[tuple[int, Sequence[clingo.Symbol]]] = []

    def keep(model: clingo.Model) -> None:
        found.append((sum(model.cost), model.symbols(atoms=True)))

    with control.solve(on_model=keep, async_=True) as handle:
        ended = handle.wait(seconds) if seconds is not None else handle.wait()
        if not ended:
            handle.cancel()
        result = handle.get()
    summary = control.statistics["summary"]
    if result.unsatisfiable:
        return _Run(None, math.inf, True)
    bound = float(sum(summary["lower"])) if not found or not result.exhausted else found[-1][0]
    best = None
    if found:
        cost, symbols = found[-1]
        choices: dict[Ground, int] = {}
        for symbol in symbols:
            if symbol.name in ("use", "bind") and len(symbol.arguments) == 2:
                instance, choice = (a.number for a in symbol.arguments)
                choices.setdefault(facts.names[instance], choice)
        best = Model(float(cost * facts.unit), choices)
    return _Run(best, float(max(0.0, bound) * facts.unit), bool(result.exhausted))


def bracket(grounder: Grounder, goal: Ground, seconds: float | None = None) -> Bracket:
    """The two optima of ``goal`` (see the module's docstring), each solver run
    given at most half of ``seconds`` (and the second what the first left);
    None: no limit. Raises :class:`Unsupported` when costs or bandwidths have no
    unit."""
    started = time.monotonic()
    facts = _facts(grounder.task, graph_of(grounder), goal)
    half = None if seconds is None else max(0.0, seconds - (time.monotonic() - started)) / 2
    relaxed = _optimum(facts, "relaxed", half)
    if relaxed.bound == math.inf:
        return Bracket(math.inf, None)
    rest = None if seconds is None else max(0.0, seconds - (time.monotonic() - started))
    exact = _optimum(facts, "exact", rest)
    return Bracket(relaxed.bound, exact.best)


def upper(grounder: Grounder, goal: Ground, seconds: float | None = None) -> Model | None:
    """The cheapest configuration that expands every instance one way (the
    ``exact`` program alone, for at most ``seconds``): what a planner built on a
    solver over the ground instances answers, without the relaxation's proof.
    The benchmarks' reference (``python -m benchmarks.engines``); None: none found."""
    return _optimum(_facts(grounder.task, graph_of(grounder), goal), "exact", seconds).best


def first(grower: Grower, goal: Ground, cheapest: float) -> Configuration | None:
    """The first configuration of cost ``cheapest`` in the thesis's order: the
    depth-first walk of 4.5 (method versions in domain order, bindings in state
    order), entering a child only while its settled cost is at most ``cheapest``
    and the relaxation, with every expansion and binding made on the way to it
    assumed, still has a model that costs at most ``cheapest``.

    The relaxation admits every completion of a derivation, so a child it rules
    out has no completion at that cost: the walk skips no configuration of cost
    ``cheapest``, and the first it completes is the first in the thesis's order
    (labels and all). Where the relaxation is as tight as the bracket (every
    shape measured), the walk goes straight down, with a solver call for each
    choice it declines and each one the last model found does not make; where
    it is not, it backtracks. ``grower`` finishes the complete
    nodes (step 4, and in distinct mode a derivation seen before is skipped);
    None: nothing costs ``cheapest``."""
    facts = _facts(grower.grounder.task, graph_of(grower.grounder), goal)
    # Core-guided under an initial bound: a refusal is a lower bound above it,
    # which usc proves as it goes (an enumeration to the bound took minutes).
    control = _grounded(facts, "relaxed", f"opt,{int(Fraction(repr(cheapest)) / facts.unit)}")
    return _walk(grower, goal, cheapest, facts, control, set())


@dataclass(frozen=True)
class Relaxation:
    """The relaxation grounded for one goal (:func:`relaxation`), to be
    optimised and walked (:func:`cheapest`)."""

    facts: _Facts
    control: clingo.Control


def relaxation(grower: Grower, goal: Ground) -> Relaxation:
    """The relaxation for ``goal``, grounded: the part of :func:`cheapest` that
    can be done before the race starts. Raises :class:`Unsupported` (costs
    without a unit)."""
    facts = _facts(grower.grounder.task, graph_of(grower.grounder), goal)
    return Relaxation(facts, _grounded(facts, "relaxed", "opt"))


def cheapest(
    grower: Grower, goal: Ground, seconds: float | None = None, grounded: Relaxation | None = None
) -> Configuration | None:
    """The first cheapest configuration in the thesis's order, with the
    relaxation alone (``grounded``, or grounded here): its optimum L (within
    ``seconds``), then the walk of :func:`first` at L, on the same grounded
    program, from L's model. Nothing costs less than a lower bound, so a
    configuration of cost L is the cheapest; the exact program's proof that one
    exists is not needed, the walk finds it. None: nothing is admissible (the
    relaxation has no model), L was not proven within ``seconds``, or no
    configuration costs L (the relaxation is looser than the thesis's planner
    here, and the walk has been through every choice it leaves). Raises
    :class:`Unsupported` (costs without a unit) and
    :class:`~cfgplan.planner.clock.OutOfTime`. What the racing solver's process
    runs."""
    prepared = grounded or relaxation(grower, goal)
    facts, control = prepared.facts, prepared.control
    found: list[tuple[int, list[clingo.Symbol]]] = []

    def keep(model: clingo.Model) -> None:
        chosen = [a for a in model.symbols(atoms=True) if a.name in ("use", "bind")]
        found.append((sum(model.cost), chosen))

    with control.solve(on_model=keep, async_=True) as handle:
        if not (handle.wait(seconds) if seconds is not None else handle.wait()):
            handle.cancel()
        result = handle.get()
    if result.unsatisfiable:
        raise Inadmissible
    if not found or not result.exhausted:
        return None  # L not proven in time
    bound, chosen = found[-1]
    control.configuration.solve.opt_mode = f"opt,{bound}"  # type: ignore[union-attr]
    return _walk(grower, goal, float(bound * facts.unit), facts, control, set(chosen))


def _walk(
    grower: Grower,
    goal: Ground,
    cheapest: float,
    facts: _Facts,
    control: clingo.Control,
    witness: set[clingo.Symbol],
) -> Configuration | None:
    """:func:`first`'s walk, with ``control`` grounded with the relaxation for
    models of cost at most ``cheapest``. ``witness``: the choices of the last
    model found (updated as the walk goes); any assumptions it makes true need
    no call."""
    import clingo

    task = grower.grounder.task

    def possible(assumed: frozenset[clingo.Symbol]) -> bool:
        """Whether the relaxation has a model of cost at most ``cheapest`` with
        ``assumed`` (the first model within the bound ends the call)."""
        if assumed <= witness:
            return True
        clock.check()

        def keep(model: clingo.Model) -> bool:
            witness.clear()
            witness.update(a for a in model.symbols(atoms=True) if a.name in ("use", "bind"))
            return False

        result = control.solve(assumptions=[(a, True) for a in assumed], on_model=keep)
        return bool(result.satisfiable)

    def atom(node: Partial, child: Partial) -> clingo.Symbol | None:
        """What ``child`` chose for ``node``'s top item, as an atom of the model."""
        item = node.stack[0]
        if item.call in node.labels:  # a functionality already in C: reused
            return None
        n = facts.calls[item.call]
        if n in facts.methods:
            return clingo.Function("use", [clingo.Number(n), clingo.Number(child.path[-1])])
        chose = child.path[-1] if len(child.path) > len(node.path) else 0
        return clingo.Function("bind", [clingo.Number(n), clingo.Number(chose)])

    # A child is checked when the walk comes to it, not when it is made: where
    # its elder sibling completes, it is never checked.
    stack: list[tuple[Partial, frozenset[clingo.Symbol]]] = [(root(goal), frozenset())]
    while stack:
        clock.check()
        node, assumed = stack.pop()
        if not possible(assumed):
            continue
        grower.stats.nodes += 1
        if node.done:
            total = task.levels.cost(node.cost)
            admitted = grower.admit(node, total) if total == cheapest else None
            if admitted is not None:
                return grower.build(admitted)
            continue
        entered = []
        grower.stats.expansions += 1
        for child in successors(grower.grounder, node):
            if isinstance(child, DeadEnd):
                grower.report.note(child)
                continue
            if task.levels.cost(child.cost) > cheapest:
                continue
            chosen = atom(node, child)
            entered.append((child, assumed if chosen is None else assumed | {chosen}))
        stack.extend(reversed(entered))
    return None


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
        parent = os.getpid()  # before the fork: the child may first run after the parent ended
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
            _answer(self.engine, parent, hear, answer)
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


def _answer(engine: Prepare, parent: int, hear: int, answer: int) -> NoReturn:
    """The child: prepare ``engine``, wait for the word on ``hear``, then write
    its answer (pickled) to ``answer``; exit without returning into the search
    it was forked from, nor flushing what the parent had buffered (``os._exit``).
    ``parent``: the search's pid, taken before the fork (on a loaded machine the
    child may first run after the parent ended; ``os.getppid()`` would then name
    the process that adopted it)."""
    code = 1
    try:
        _die_with(parent)
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
