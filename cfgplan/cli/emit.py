"""``cfgplan emit DOMAIN STATE``: per-robot executable code for a configuration (thesis 5.1-5.3).

The configuration of the given rank is sorted, divided per robot and
translated: one file per robot (``emil.lisp`` with the LET/LAMBDA form of 5.3,
or ``emil.py`` for :mod:`cfgplan.runtime`; plus ``run_all.py`` for Python)
and the whole configuration description in ``configuration.txt``, which ends
with the robot -> file table. A robot's file name is made safe by
:mod:`cfgplan.safe_names` (``../../x`` cannot leave the folder). The files are
written all at once by :func:`cfgplan.files.write_folder`; existing files are
never overwritten without ``--force``.
"""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from cfgplan.backends.lisp import to_lisp
from cfgplan.backends.python import run_all, to_python
from cfgplan.backends.wiring import RobotPart, deploy
from cfgplan.cli.app import EXIT_NONE, app, say
from cfgplan.cli.plan import DomainArg, GoalOpt, StateArg, WeightsOpt, load_problem
from cfgplan.configuration.cost import fmt
from cfgplan.configuration.describe import to_text
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import printable
from cfgplan.files import write_folder
from cfgplan.notation import call_text
from cfgplan.planner import plan
from cfgplan.planner.explain import explain
from cfgplan.problem import Problem


class Lang(StrEnum):
    lisp = "lisp"
    python = "python"


RankOpt = Annotated[
    int, typer.Option("--rank", min=1, help="Which configuration, cheapest first (default 1).")
]
DESCRIPTION = "configuration.txt"
RUN_ALL = "run_all.py"


def choose(problem: Problem, rank: int) -> Configuration:
    """The configuration of ``rank`` (1: the cheapest); exit 3 when there are fewer."""
    configs, search = plan(problem.task, problem.goal_call, limit=rank)
    if len(configs) < rank:
        if not configs:
            say("\n".join(explain(search.report, call_text(problem.goal_call))))
        else:
            say(f"cfgplan: only {len(configs)} configuration(s), no rank {rank}")
        raise typer.Exit(EXIT_NONE)
    return configs[rank - 1]


def title(problem: Problem, config: Configuration, rank: int) -> str:
    return f"Configuration rank {rank}, cost {fmt(config.cost)}, for {call_text(problem.goal_call)}"


def files(problem: Problem, config: Configuration, rank: int, lang: Lang) -> dict[str, str]:
    """File name -> text, in the order they are written."""
    parts = deploy(config, problem.domain)
    head = title(problem, config, rank)
    suffix = ".lisp" if lang is Lang.lisp else ".py"
    out: dict[str, str] = {}
    for part in parts:
        name = part.stem + suffix
        out[name] = _lisp(part, head) if lang is Lang.lisp else to_python(part, head)
    if lang is Lang.python:
        out[RUN_ALL] = run_all(parts, head)
    out[DESCRIPTION] = to_text(config, problem.state.media) + "\n" + file_table(parts, suffix)
    return out


def file_table(parts: tuple[RobotPart, ...], suffix: str) -> str:
    """The robot -> file table that ends ``configuration.txt``, as LISP comments;
    names are shown with unsafe characters escaped."""
    lines = [";; Files, one per robot (cfgplan emit):"]
    lines += [f";;   {printable(p.robot)} -> {p.stem}{suffix}" for p in parts]
    return "\n".join(lines) + "\n"


def _lisp(part: RobotPart, head: str) -> str:
    comments = [
        f"{part.robot}'s executable individual configuration (thesis 5.3; cfgplan emit).",
        f"{head}.",
        "",
        *part.individual.text().splitlines(),
    ]
    return to_lisp(part, comments)


@app.command()
def emit(
    domain: DomainArg,
    state: StateArg,
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Directory to write the files to.")
    ],
    goal: GoalOpt = None,
    rank: RankOpt = 1,
    weights: WeightsOpt = None,
    lang: Annotated[Lang, typer.Option("--lang", help="Target language.")] = Lang.lisp,
    force: Annotated[bool, typer.Option("--force", help="Overwrite existing files.")] = False,
) -> None:
    """Write one executable file per robot for a configuration (thesis 5.1-5.3).

    Exit codes: 0 written, 1 invalid input or existing files, 2 usage,
    3 no configuration of that rank.
    """
    problem = load_problem(domain, state, goal, weights)
    texts = files(problem, choose(problem, rank), rank, lang)
    write_folder(output, {name: text.encode("utf-8") for name, text in texts.items()}, force)
    for name in texts:
        say(f"wrote {output / name}")
