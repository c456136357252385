"""Every command of ``cfgplan``, in one map: name -> ``module:attribute``.

The map serves the list of commands (the help, shell completion, the
reference page), the look-up of one, and its lazy import (click's lazily
loaded subcommands: :class:`cfgplan.cli.root.Group` imports a command's module
only when the command line, or the help, needs it). A command module
registers nothing by being imported: it marks its function with
:func:`command` (the settings typer's ``app.command`` takes) and the map
names it. This module imports nothing of cfgplan's command line, so that
every other module of it may import this one without a cycle.
"""

from __future__ import annotations

import importlib

TYPE_CHECKING = False  # as typing.TYPE_CHECKING, without importing typing (3 ms)
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any, TypeVar

    _F = TypeVar("_F", bound=Callable[..., Any])

COMMANDS: dict[str, str] = {
    "check": "cfgplan.cli.check:check",
    "emit": "cfgplan.cli.emit:emit",
    "keys": "cfgplan.cli.keys:keys_app",
    "launch": "cfgplan.cli.launch:launch",
    "plan": "cfgplan.cli.plan:plan",
    "record": "cfgplan.cli.record:record",
    "render": "cfgplan.cli.render:render",
    "report": "cfgplan.cli.report:report",
    "router": "cfgplan.cli.router:router",
    "run": "cfgplan.cli.run:run",
    "simulate": "cfgplan.cli.simulate:simulate",
}
"""Each command's name and where it is: a function marked with :func:`command`,
or a typer app of subcommands (``keys``)."""

QUICK_EXIT = frozenset({"check", "emit", "plan", "render"})
"""The commands that hold nothing open once they return (their files written
and closed, no thread, no network session, no recording): the console script
ends them without tearing the interpreter down (:func:`cfgplan.cli.app._leave`)."""

SETTINGS = "__cfgplan_command__"
"""The attribute :func:`command` sets on a command's function: typer's settings."""


def command(**settings: Any) -> Callable[[_F], _F]:
    """Mark a function as a command, with the settings of typer's
    ``app.command`` (``short_help=...``); :data:`COMMANDS` names it."""

    def mark(function: _F) -> _F:
        setattr(function, SETTINGS, settings)
        return function

    return mark


def module_of(name: str) -> str:
    """The module of command ``name`` (``cfgplan.cli.plan``)."""
    return COMMANDS[name].partition(":")[0]


def load(name: str) -> object:
    """What command ``name`` is: its module imported, the attribute the map names."""
    module, _, attribute = COMMANDS[name].partition(":")
    return getattr(importlib.import_module(module), attribute)


def version_line() -> str:
    """What ``cfgplan --version`` prints (without its line break): the version
    is :data:`cfgplan.__version__`, which the package metadata is built from."""
    from cfgplan import __version__

    return f"cfgplan {__version__}"
