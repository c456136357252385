"""Every tuning constant and strategy switch of the planner, in one frozen
object: a search is given a :class:`SearchOptions`, and tests pass
one instead of patching module constants. None of them changes what is found
or its order, only how much work finding it takes (the property tests of
``tests/planner`` check that with the extreme settings).

Not here: the sizes of what a task's bounds keep (made once per task and
shared by every search of it, :func:`cfgplan.planner.plan.analysis`), which no
search could set for itself: how many stacks' counts are kept
(:data:`cfgplan.planner.partition.STACKS`), and where
:func:`cfgplan.planner.bound.least` changes its way of meeting parts
(``WIDE``, ``MOST_WIDE``, ``GROUPS``: the same floats either way, each way
tested on its own in ``tests/planner/test_parts.py``), and when an evaluation
of the partitioned bound starts from a sibling's
(:attr:`cfgplan.planner.partition.Least.reuse`, ``smallest``: the same floats
either way). Tests read them and never patch them."""

from __future__ import annotations

from dataclasses import dataclass

RACE = 1_000
"""The :attr:`SearchOptions.race` of ``cfgplan plan``: about a tenth of a second
of search (the thesis's instances take under a hundred steps), after which the
solver's process costs the search nothing on a second core."""


@dataclass(frozen=True)
class SearchOptions:
    """How a search works; the defaults are the measured ones (benchmarks)."""

    warm: int = 32
    """Nodes a search prices (settles) before it tries the stronger bound at
    all: a small search (the thesis's instances) is over before it could pay
    for itself. Counted in nodes priced, not taken: where every expansion has
    many children (fusion) the bound is soon worth its cost."""

    trial: int = 4
    """Refinements by the stronger bound a search tries before it may give that
    bound up: from then on, when fewer than one refinement in :attr:`pays` paid
    (pruned a node, raised its priority past the next node's, so that another
    node is taken first, or priced some of its children above their own bound,
    :mod:`cfgplan.planner.partition`), the bound is dropped for the rest of the
    search, unless it was at least the first bound every time: then it is
    kept, for :attr:`rely` to drop the first instead (where both are exact, a
    deep chain, the stronger one priced from its last evaluation is the
    cheaper). Where it seldom pays (build-wall, the wall and relay families)
    it only costs time; where it helps (ecology, fusion, media-tight) most of
    its raises pay. Dropping an admissible bound never changes the answer,
    only how many nodes are taken (tests/planner/test_pricer.py)."""

    pays: int = 4
    """See :attr:`trial`."""

    rely: int = 32
    """Refinements after which, if the stronger bound was at least the first
    one every time, the first one is no longer computed (only whether a node
    can complete is: :attr:`cfgplan.planner.pricer.Pricer.feasible`): where the
    stronger bound always dominates (fusion), the first adds only its cost.
    The open nodes keep the priorities they have (lower bounds still)."""

    together: int = 8
    """Estimates in which the first bound's together least cost (an item's
    least functionalities and channels as one sum,
    :class:`cfgplan.planner.bound.Together`) may fail to raise the bound
    before a search stops counting it; once it has raised one, it is counted
    to the end. Exact on a deep chain at once; on the gateway family it
    never raises the bound and costs only its time."""

    one_pass: int = 5_000
    """Nodes the first walk of ``--all``, over every cost at once, may take
    before it has listed anything (:mod:`cfgplan.planner.search`)."""

    most_held: int = 250_000
    """Configurations one window of ``--all`` may hold before its upper edge
    comes down."""

    media: bool = True
    """Price as impossible an expansion whose own global channels the media
    cannot carry on top of a node's (:mod:`cfgplan.planner.partial`, in the
    partitioned bound); False prices it as if the media carried anything.
    The configurations found are the same (a completion always fits the
    media: step 4 checks it), only the work to find them differs."""

    components: bool = True
    """Search the goal's independent parts apart when it has some
    (:mod:`cfgplan.planner.combine`; the ``limit`` cheapest only)."""

    splits: bool = True
    """Price the children of a node the stronger bound refined from that
    node's split, so that most are never refined themselves
    (:mod:`cfgplan.planner.partition`); False prices each child alone."""

    replays: bool = True
    """In the best-first search, do a sub-derivation closed before again in
    one step where the same method instance is on top again, beside a node
    for its other derivations priced at their floor
    (:mod:`cfgplan.planner.grow`); False walks it step by step."""

    replay_trial: int = 4
    """Sub-derivations remembered but not replayed a search may meet before
    it has replayed one (too short, a dead end on the walk, or a deviation
    costing no more than the replay: the wall family's equal costs): then it
    stops replaying, and remembering, for the rest of the search."""

    replay_worth: int = 32
    """The fewest method expansions replays must be able to save in one
    derivation (every later occurrence of every repeated instance, at its
    longest) for a search to remember anything: the thesis's build-a-wall,
    with a few short repeats, is over before remembering would pay."""

    replay_least: int = 4
    """The fewest method expansions a sub-derivation must have to be replayed:
    a shorter walk costs less than pricing its deviations (the wall family's
    are one or two)."""

    solver: bool = False
    """``-k 1`` by the solver (:mod:`cfgplan.planner.solver`): the cheapest cost
    bracketed, then the first configuration of that cost in the thesis's order
    by a walk the relaxation guides; the same configuration as the search's,
    found without its ties. Where the bracket does not close in the time
    given (or costs have no unit), the search plans as without it."""

    race: int | None = None
    """``-k 1``: the steps of the clock (:func:`cfgplan.planner.clock.check`, a
    measure of work that is the same on every machine) the search makes alone
    before the solver's process is started beside it, the first of the two to
    end answering (:mod:`cfgplan.planner.solver`); None: the search alone.
    ``cfgplan plan`` races after :data:`RACE` steps (its ``--engine both``); a
    library caller chooses (a robot's runtime, a long-lived process with Zenoh's
    threads, plans small problems and does not race)."""
    dive: bool = True
    """When a limit stops the search before anything was proven, dive greedily
    from the open nodes for a configuration (:mod:`cfgplan.planner.search`,
    shown with ``*``); False reports that nothing was found."""

    ahead_least: int = 10_000
    """The least work the look-ahead of ``-k N`` may do (:mod:`cfgplan.planner.search`)."""

    grace: float = 0.35
    """Seconds past the time limit the greedy dive may take when nothing was
    proven (the run ends within the limit plus half a second)."""

    explain_seconds: float = 2.0
    """The least time the search for "why nothing" may take (more if
    planning took more)."""
