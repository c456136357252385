"""``cfgplan emit DOMAIN STATE``: per-robot executable code for a configuration (thesis 5.1-5.3).

The configuration of the given rank is sorted, divided per robot and
translated: one file per robot (by default ``emil.py`` for
:mod:`cfgplan.runtime`, plus ``run_all.py``; with ``--lang lisp``
``emil.lisp``, the LET/LAMBDA form of 5.3)
and the whole configuration description in ``configuration.txt``, which ends
with the robot -> file table. A robot's file name is made safe by
:mod:`cfgplan.safe_names` (``../../x`` cannot leave the folder). The files are
written all at once, with the record of what was written, by
:func:`cfgplan.emission.write_emission`: ``--force`` replaces an earlier
emission in the folder whole, and files cfgplan did not write are never
overwritten or removed.
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

from pathlib import Path
from typing import Annotated

import typer

from cfgplan.backends.lisp import to_lisp
from cfgplan.backends.python import run_all, to_python
from cfgplan.backends.wiring import RobotPart, deploy
from cfgplan.cli.app import say
from cfgplan.cli.options import (
    DomainArg,
    GoalOpt,
    RankOpt,
    StateArg,
    WeightsOpt,
    choice_of,
    choose,
    completing,
    load_problem,
)
from cfgplan.cli.registry import command
from cfgplan.configuration.cost import fmt
from cfgplan.configuration.describe import to_text
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import printable
from cfgplan.emission import RECORD, write_emission
from cfgplan.notation import call_text
from cfgplan.problem import Problem
from cfgplan.security.identity import ProblemId, problem_id

LANGS = ("lisp", "python")
DESCRIPTION = "configuration.txt"
RUN_ALL = "run_all.py"


def title(problem: Problem, config: Configuration, rank: int) -> str:
    return f"Configuration rank {rank}, cost {fmt(config.cost)}, for {call_text(problem.goal_call)}"


def files(
    problem: Problem,
    config: Configuration,
    rank: int,
    lang: str,
    identity: ProblemId | None = None,
) -> dict[str, str]:
    """File name -> text, in the order they are written; ``lang`` is ``lisp`` or
    ``python``; ``identity``, the problem's, is announced by each Python robot."""
    parts = deploy(config, problem.domain)
    head = title(problem, config, rank)
    suffix = ".lisp" if lang == "lisp" else ".py"
    out: dict[str, str] = {}
    for part in parts:
        name = part.stem + suffix
        out[name] = _lisp(part, head) if lang == "lisp" else to_python(part, head, identity)
    if lang == "python":
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


@command(short_help="Write one executable file per robot for a configuration (5.1-5.3).")
def emit(
    domain: DomainArg,
    state: StateArg,
    output: Annotated[
        Path,
        typer.Option("-o", "--output", metavar="DIR", help="Directory to write the files to."),
    ],
    goal: GoalOpt = None,
    rank: RankOpt = 1,
    weights: WeightsOpt = None,
    lang: Annotated[
        str,
        typer.Option(
            "--lang",
            metavar="lisp|python",
            parser=choice_of(LANGS, "a language"),
            autocompletion=completing(LANGS),
            help="Target language: Python, runnable with cfgplan.runtime (default), or "
            "the thesis's LET/LAMBDA form (lisp).",
            show_default=False,
        ),
    ] = "python",
    force: Annotated[
        bool, typer.Option("--force", help="Replace an earlier emission in DIR.")
    ] = False,
) -> None:
    """Write one executable file per robot for a configuration (thesis 5.1-5.3).

    Exit codes: 0 written, 1 invalid input or existing files, 2 usage,
    3 no admissible configuration (or none of that rank).
    """
    problem = load_problem(domain, state, goal, weights)
    texts = files(problem, choose(problem, rank), rank, lang, problem_id(problem, domain, state))
    removed = write_emission(
        output, {name: text.encode("utf-8") for name, text in texts.items()}, force
    )
    for name in [*texts, RECORD]:  # the record too: what --force may replace (emission.py)
        say(f"wrote {output / name}")
    for path in removed:
        say(f"removed {path} (from the earlier emission)")
