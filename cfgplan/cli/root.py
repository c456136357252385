"""The typer application behind ``cfgplan``: its root command, the command
class every subcommand uses, and the ``--version`` option.

Importing this module loads typer (and with it click); :mod:`cfgplan.cli.app`
imports it only when a command runs, so that ``cfgplan --version`` and the
top-level ``--help`` answer without it (:mod:`cfgplan.cli.help_text`). Each
command module adds its command here (``@app.command``).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from typing import Annotated, Any, TypeVar

import typer
from typer.core import TyperCommand, TyperGroup

from cfgplan.cli.app import version_line

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
    """The root command: its help lists the commands by name, not in the order
    their modules happened to be imported (a test, or a future command module
    importing another, would reorder typer's list), so the help is the same in
    every process and matches the pre-rendered :mod:`cfgplan.cli.help_text`."""

    def list_commands(self, ctx: Any) -> list[str]:
        return sorted(self.commands)


_F = TypeVar("_F", bound=Callable[..., Any])


class _Typer(typer.Typer):
    """Every command is a :class:`Command`."""

    def command(self, *args: Any, **kwargs: Any) -> Callable[[_F], _F]:
        kwargs.setdefault("cls", Command)
        return super().command(*args, **kwargs)


app = _Typer(
    name="cfgplan",
    cls=Group,
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
    first), every command registered (it imports them all), with its line break."""
    from unittest import mock

    import cfgplan.cli.commands  # noqa: F401  (registers every command)

    group = typer.main.get_command(app)
    with (
        mock.patch.dict(os.environ, {"COLUMNS": str(columns)}),
        typer.Context(group, info_name="cfgplan", **group.context_settings) as ctx,
    ):
        return group.get_help(ctx) + "\n"


def write_help_module() -> str:
    """The source of :mod:`cfgplan.cli.help_text`, generated from :func:`render_help`."""
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


if __name__ == "__main__":  # run as a script: the commands register on cfgplan.cli.root.app
    from pathlib import Path

    from cfgplan.cli import root

    target = Path(root.__file__).with_name("help_text.py")
    target.write_text(root.write_help_module(), "utf-8")
    print(f"wrote {target}")
