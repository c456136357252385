"""``cfgplan router``: a Zenoh router the robots of a society are clients of.

The logic is :mod:`cfgplan.runtime.router`; this module reads the command
line. ``cfgplan launch`` starts one itself (its default topology without
``--keys``); on several hosts, start it on one of them and give every robot
``--router tcp/THAT-HOST:7447`` (``zenohd`` or ``rmw_zenohd`` serve as well).
"""

# No ``from __future__ import annotations``: typer reads the commands'
# annotations as objects, with no string to evaluate for each option
# (start-up, docs/development.md).

from pathlib import Path
from typing import Annotated

import typer

from cfgplan.cli.options import option, parsed
from cfgplan.cli.registry import command
from cfgplan.diagnostics import run_error
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.options import LEASE, ZENOH_CONFIG, endpoint
from cfgplan.runtime.zenoh_config import DEFAULT_LEASE


@command(short_help="Run a Zenoh router for robots started with --router.")
def router(
    listen: Annotated[
        list[str] | None,
        typer.Option(
            "--listen",
            metavar="ENDPOINT",
            parser=parsed(endpoint),
            help="Listen on ENDPOINT (repeatable; default tcp/[::]:7447, Zenoh's port on every "
            "interface, as zenohd).",
            show_default=False,
        ),
    ] = None,
    lease: Annotated[float | None, option(LEASE)] = None,
    zenoh_config: Annotated[Path | None, option(ZENOH_CONFIG)] = None,
) -> None:
    """Run a Zenoh router (Zenoh's own, in router mode) until Ctrl-C or SIGTERM.

    Each robot started with --router ENDPOINT holds one connection, to this router,
    instead of one to every other robot. Without keys: anyone who reaches the
    router reaches the society. Exit codes: 0 stopped, 1 it could not open.
    """
    from cfgplan.runtime.router import DEFAULT_LISTEN, RouterOptions, serve

    try:
        options = RouterOptions(
            listen=tuple(listen or (DEFAULT_LISTEN,)),
            lease=DEFAULT_LEASE if lease is None else lease,
            config_file=None if zenoh_config is None else str(zenoh_config),
        )
        serve(options, lambda line: typer.echo(line))
    except RunError as exc:
        raise run_error(exc) from None
