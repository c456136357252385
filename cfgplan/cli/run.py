"""``cfgplan run DOMAIN STATE --impl IMPL``: execute a configuration in process (chapter 5).

The configuration of the given rank is sorted, divided and wired as for
``cfgplan emit``, then every robot runs in this process (global channels
joined by the in-process transport), one cycle each in turn, calling the
implementations declared in IMPL. Printed: what each action functionality
received, then per functionality how often it ran; ``--trace`` prints every call.
"""

from __future__ import annotations

from typing import Annotated

import typer

from cfgplan.backends.wiring import deploy
from cfgplan.cli.app import app
from cfgplan.cli.emit import RankOpt, choose, title
from cfgplan.cli.plan import DomainArg, GoalOpt, StateArg, WeightsOpt, load_problem
from cfgplan.runtime import Registry, describe, society, summary


@app.command()
def run(
    domain: DomainArg,
    state: StateArg,
    impl: Annotated[
        str,
        typer.Option(
            "--impl",
            help="Implementations: a module name (pkg.impl) or a .py file declaring them "
            "with @functionality (cfgplan.runtime).",
        ),
    ],
    goal: GoalOpt = None,
    rank: RankOpt = 1,
    weights: WeightsOpt = None,
    cycles: Annotated[int, typer.Option("--cycles", min=1, help="How many cycles.")] = 5,
    trace: Annotated[
        bool, typer.Option("--trace", help="Print every call, not only what actions received.")
    ] = False,
) -> None:
    """Execute a configuration with all its robots in this process (thesis 5.2, 5.3).

    Exit codes: 0 ran, 1 invalid input or a failing implementation, 2 usage,
    3 no configuration of that rank.
    """
    problem = load_problem(domain, state, goal, weights)
    config = choose(problem, rank)
    registry = Registry.load(impl)
    robots = society(deploy(config, problem.domain), registry)
    names = ", ".join(r.name for r in robots.robots)
    typer.echo(f"{title(problem, config, rank)}: {names}; {cycles} cycle(s)")
    robots.run(cycles)
    for event in robots.events:
        if trace or (event.action and event.status == "ran"):
            typer.echo(describe(event))
    for line in summary(robots.events):
        typer.echo(line)
