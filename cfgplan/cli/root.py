"""The typer application behind ``cfgplan``: its root command, the command
class every subcommand uses, and the ``--version`` option.

Importing this module loads typer (and with it click); :mod:`cfgplan.cli.app`
imports it only when a command runs, so that ``cfgplan --version`` and the
top-level ``--help`` answer without it (:mod:`cfgplan.cli.help_text`). The
root group finds its commands in the one map of them,
:data:`cfgplan.cli.registry.COMMANDS`, and imports a command's module only
when it is asked for that command (click's lazily loaded subcommands): no
command module registers itself, and this module imports none of them, nor
:mod:`cfgplan.cli.app`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from typing import Annotated, Any, TypeVar

import typer
from typer.core import TyperCommand, TyperGroup

from cfgplan.cli.registry import COMMANDS, SETTINGS, load, version_line

HELP_WIDTH = 80
"""The terminal width the top-level help is rendered at for the fast path:
click's help is as wide as the terminal, but at most 80 columns."""


class Command(TyperCommand):
    """A cfgplan command: its usage line names the arguments as ``DOMAIN
    STATE`` (typer would write ``{DOMAIN} {STATE}``)."""

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        pieces: list[str] = super().collect_usage_pieces(ctx)
        return [re.sub(r"^\{([^{}]+)\}", r"\1", p) for p in pieces]  # {RUN}... as RUN...


class Group(TyperGroup):
    """A group of commands whose help lists them by name, not in the order
    they were registered, so that the help is the same in every process and
    matches the pre-rendered :mod:`cfgplan.cli.help_text` (``keys`` is one)."""

    def list_commands(self, ctx: Any) -> list[str]:
        return sorted(self.commands)


class Root(Group):
    """The root command: its commands are those of the one map of them
    (:data:`~cfgplan.cli.registry.COMMANDS`), each loaded when it is first
    asked for (click's lazily loaded subcommands)."""

    def list_commands(self, ctx: Any) -> list[str]:
        return sorted({*COMMANDS, *self.commands})

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        found = self.commands.get(cmd_name)
        if found is None and cmd_name in COMMANDS:
            found = self.commands[cmd_name] = click_command(cmd_name)
        return found

    def resolve_command(self, ctx: Any, args: list[str]) -> Any:
        """As typer's; a name that is no command's first loads every command,
        so that typer's "Did you mean" is drawn from them all."""
        if args and args[0] not in COMMANDS and args[0] not in self.commands:
            for name in COMMANDS:
                self.get_command(ctx, name)
        return super().resolve_command(ctx, args)


def click_command(name: str) -> Any:
    """The click command of ``name``: its function, marked with
    :func:`~cfgplan.cli.registry.command`, made a typer command; or its
    typer app of subcommands."""
    target = load(name)
    if isinstance(target, typer.Typer):
        return typer.main.get_command(target)
    if not callable(target) or not hasattr(target, SETTINGS):
        raise TypeError(f"{COMMANDS[name]} is not marked with cfgplan.cli.registry.command")
    one = _Typer(add_completion=False, pretty_exceptions_enable=False, rich_markup_mode=None)
    one.command(name=name, **getattr(target, SETTINGS))(target)
    return typer.main.get_command(one)


_F = TypeVar("_F", bound=Callable[..., Any])


class _Typer(typer.Typer):
    """Every command is a :class:`Command`."""

    def command(self, *args: Any, **kwargs: Any) -> Callable[[_F], _F]:
        kwargs.setdefault("cls", Command)
        return super().command(*args, **kwargs)


app = _Typer(
    name="cfgplan",
    cls=Root,
    help="Plan-based configuration of robot societies (R. Lundh, 2006).",
    no_args_is_help=True,
    add_completion=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        typer.echo(version_line())
        raise typer.Exit(0)


@app.callback()
def _options(
    show_version: Annotated[
        bool,
        typer.Option(
            "--version", is_eager=True, callback=_version, help="Print cfgplan's version and exit."
        ),
    ] = False,
) -> None:
    """Plan-based configuration of robot societies (R. Lundh, 2006): plan, draw,
    emit and run configurations of robots lending each other functionalities."""


def render_help(columns: int = HELP_WIDTH) -> str:
    """The top-level help as typer prints it on a terminal ``columns`` wide
    (click reads the width as :func:`shutil.get_terminal_size` does, ``COLUMNS``
    first), with its line break; listing the commands loads them all."""
    from unittest import mock

    group = typer.main.get_command(app)
    with (
        mock.patch.dict(os.environ, {"COLUMNS": str(columns)}),
        typer.Context(group, info_name="cfgplan", **group.context_settings) as ctx,
    ):
        return group.get_help(ctx) + "\n"


def write_help_module() -> str:
    """The source of :mod:`cfgplan.cli.help_text`, generated from :func:`render_help`."""
    import json

    return (
        '"""The top-level help of ``cfgplan`` (``--help``, ``-h``, and bare ``cfgplan``)\n'
        f"as typer renders it at {HELP_WIDTH} columns, printed without loading typer.\n\n"
        "Generated from the typer app by ``python -m cfgplan.cli.root``: do not edit;\n"
        "tests/cli/test_startup.py fails when it drifts from the app.\n"
        '"""\n\n'
        f"WIDTH = {HELP_WIDTH}\n"
        "HELP = (\n"
        + "".join(f"    {json.dumps(line)}\n" for line in render_help().splitlines(keepends=True))
        + ")\n"
    )


if __name__ == "__main__":  # run as a script: rewrite help_text.py
    from pathlib import Path

    from cfgplan.cli import root

    target = Path(root.__file__).with_name("help_text.py")
    target.write_text(root.write_help_module(), "utf-8")
    print(f"wrote {target}")
