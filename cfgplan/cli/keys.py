"""``cfgplan keys new SOCIETY -o DIR``: a society's certificate authority and its members' keys;
``cfgplan keys renew NAME -o DIR``: one member's key rotated (:mod:`cfgplan.security.renew`).

One key and certificate per robot and device of a state (``--domain DOMAIN
--state STATE``) or per ``--robot NAME``, per ``--operator NAME`` tool, and
one for the society's router (``cfgplan router --keys``; ``--router NAME``
names it), signed by a new certificate authority of the society
(:mod:`cfgplan.security.keys`). ``--keys DIR`` on ``cfgplan run --robot`` and
on the emitted robot programs then opens every session with TLS, mutual
authentication and access control by certificate name
(:mod:`cfgplan.security.zenoh_tls`). The coordinators, the robots that may
send switches (5.5), are those a goal of the state names first, or
``--coordinator NAME``. Nothing secret is printed: only which file is which.

Needs the ``cryptography`` package (``pip install 'cfgplan[keys]'``); a robot
that only uses keys does not.
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

from pathlib import Path
from typing import Annotated

import typer

from cfgplan.cli.app import usage_error
from cfgplan.cli.options import count_of, load_problem
from cfgplan.cli.root import Command, Group
from cfgplan.diagnostics import printable, run_error
from cfgplan.runtime.errors import RunError
from cfgplan.security.keys import ROUTER, Member

keys_app = typer.Typer(
    name="keys",
    cls=Group,
    no_args_is_help=True,
    help="Make a society's keys: TLS with mutual authentication for its robots; renew one "
    "robot's key.",
    short_help="Make or renew a society's keys for TLS with mutual authentication.",
    context_settings={"help_option_names": ["-h", "--help"]},
    add_completion=False,  # as the root's subcommand: completion is the root's
    rich_markup_mode=None,
    pretty_exceptions_enable=False,
)
"""``cfgplan keys``: the root group loads it by name (:data:`cfgplan.cli.registry.COMMANDS`)."""

DEFAULT_DAYS = 730


class name(str):
    """A society's name (lower case: typer shows an argument's type by its class
    name, ``SOCIETY <name>``)."""


def _name(text: str) -> name:
    """A society's name: not empty."""
    if not text:
        raise typer.BadParameter("the society name is empty")
    return name(text)


def _state_members(domain: Path, state: Path) -> tuple[list[str], list[str]]:
    """The robots and devices of a state, and the robots its goals name first."""
    problem = load_problem(domain, state, None, None, sequence=True)
    agents = list(problem.task.agents)
    leading = []
    for call in problem.goal_calls:
        first = next((a for a in call[1:] if a in agents), None)
        if first is not None and first not in leading:
            leading.append(first)
    return agents, leading


def _who(member: Member) -> str:
    """A member as the output names it: ``robot Emil``, ``operator console``, ``the router``."""
    if (member.kind, member.name) == ("router", ROUTER):
        return "the router"
    return f"{member.kind} {member.name}"


@keys_app.command("new", cls=Command)
def new(
    society: Annotated[
        name,
        typer.Argument(
            metavar="SOCIETY", parser=_name, help="The society's name (as --society of run)."
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "--output", "-o", metavar="DIR", help="The folder to write (made with mode 0700)."
        ),
    ],
    domain: Annotated[
        Path | None,
        typer.Option("--domain", metavar="DOMAIN", help="The domain of --state."),
    ] = None,
    state: Annotated[
        Path | None,
        typer.Option(
            "--state",
            metavar="STATE",
            help="Keys for every robot and device of this state (with --domain).",
        ),
    ] = None,
    robots: Annotated[
        list[str] | None,
        typer.Option("--robot", metavar="NAME", help="Keys for this robot (repeatable)."),
    ] = None,
    operators: Annotated[
        list[str] | None,
        typer.Option(
            "--operator",
            metavar="NAME",
            help="Keys for an operator tool, which may watch the society and send nothing "
            "(repeatable).",
        ),
    ] = None,
    router: Annotated[
        str,
        typer.Option(
            "--router",
            metavar="NAME",
            help="The name of the society's router, whose key is made too (default "
            f"{ROUTER}; cfgplan router --keys DIR uses it).",
            show_default=False,
        ),
    ] = ROUTER,
    coordinators: Annotated[
        list[str] | None,
        typer.Option(
            "--coordinator",
            metavar="NAME",
            help="A robot that may send switches (repeatable; default: the robots the "
            "state's goals name first).",
        ),
    ] = None,
    days: Annotated[
        int,
        typer.Option(
            "--days",
            metavar="N",
            parser=count_of(1),
            help=f"Days the certificates are valid (default {DEFAULT_DAYS}).",
            show_default=False,
        ),
    ] = DEFAULT_DAYS,
    force: Annotated[
        bool, typer.Option("--force", help="Replace the society's keys in DIR.")
    ] = False,
) -> None:
    """Make a society's certificate authority and a key and certificate per robot, device
    and operator tool, and the society's router's, for --keys DIR on cfgplan run, the
    emitted robot programs, cfgplan router and cfgplan launch.

    Writes DIR/ca.pem and DIR/ca.key (the authority: keep ca.key off the robots),
    per member NAME.pem and NAME.key (its name in lower case), and DIR/society.json
    (the members and what they may do). A robot's host needs society.json, ca.pem
    and its own two files; so does the router's. Exit codes: 0 written, 1 invalid
    input, 2 usage.
    """
    if (domain is None) != (state is None):
        usage_error("give --domain DOMAIN and --state STATE together", "--state")
    names = list(robots or ())
    leading = list(coordinators or ())
    if state is not None and domain is not None:
        agents, first = _state_members(domain, state)
        names = list(dict.fromkeys([*agents, *names]))
        leading = leading or first
    if not names:
        usage_error("no robot: give --domain and --state, or --robot NAME", "--robot")
    if not leading:
        usage_error(
            "which robot may send switches? give --coordinator NAME (the robot of the goal)",
            "--coordinator",
        )
    from cfgplan.security.keys import make_society, plan_society, write_society

    if not router:
        usage_error("the router's name is empty", "--router")
    try:
        plan = plan_society(str(society), names, list(operators or ()), leading, [router])
        written = write_society(output, make_society(plan, days), force)
    except RunError as exc:
        raise run_error(exc) from None
    members = {m.stem: m for m in plan.members}
    what = {
        "ca.pem": "the society's certificate authority (to every member)",
        "ca.key": "the authority's private key (keep it off the robots)",
        "society.json": "the members and what each may do (to every member)",
    }
    for m in plan.members:
        role = " (coordinator)" if m.coordinator else ""
        who = _who(m)
        what[f"{m.stem}.pem"] = f"{who}'s certificate, {m.common_name}{role}"
        what[f"{m.stem}.key"] = f"{who}'s private key (to its host only)"
    width = max(len(p.name) for p in written)
    lines = [f"society {plan.society}: keys for {len(members)} member(s) in {output}/ (0700)"]
    lines += [f"  {path.name:<{width}}  {what[path.name]}" for path in written]
    typer.echo(printable("\n".join(lines), keep="\n"))  # names from the input, escaped


@keys_app.command("renew", cls=Command)
def renew(
    member: Annotated[
        str,
        typer.Argument(
            metavar="NAME", help="The robot (or operator tool, or router) whose key is replaced."
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "--output",
            "-o",
            metavar="DIR",
            help="The society's keys, where cfgplan keys new wrote them (with ca.key).",
        ),
    ],
    days: Annotated[
        int,
        typer.Option(
            "--days",
            metavar="N",
            parser=count_of(1),
            help=f"Days the new certificate is valid (default {DEFAULT_DAYS}).",
            show_default=False,
        ),
    ] = DEFAULT_DAYS,
) -> None:
    """Give one robot (or operator tool, or the router) a new key and certificate, signed by
    the society's own authority, and make the old certificate useless where society.json
    is renewed.

    Replaces DIR/NAME.pem and DIR/NAME.key (NAME in lower case) and DIR/society.json,
    which now names the new certificate only (its common name ends in @2, @3, ...).
    Give the robot's host its two new files and every host the new society.json, then
    restart them: a member still holding the old society.json admits the old certificate.
    Exit codes: 0 written, 1 invalid input, 2 usage.
    """
    if not member:
        usage_error("the name is empty", "NAME")
    from cfgplan.security.keys import write_society
    from cfgplan.security.renew import renew as renew_member

    try:
        old, new, files = renew_member(output, member, days)
        written = write_society(output, files, force=True)
    except RunError as exc:
        raise run_error(exc) from None
    what = {
        f"{new.stem}.pem": f"{_who(new)}'s new certificate, {new.common_name} (to its host)",
        f"{new.stem}.key": f"{_who(new)}'s new private key (to its host only)",
        "society.json": f"admits {new.common_name}, no longer {old.common_name} (to every host)",
    }
    width = max(len(p.name) for p in written)
    lines = [f"{_who(new)}: key generation {new.generation} in {output}/"]
    lines += [f"  {path.name:<{width}}  {what[path.name]}" for path in written]
    lines.append(
        f"the old certificate ({old.common_name}) can do nothing with a member that has the "
        "new society.json; until then that member still admits it"
    )
    typer.echo(printable("\n".join(lines), keep="\n"))
