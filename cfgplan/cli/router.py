"""``cfgplan router``: a Zenoh router the robots of a society are clients of.

The logic is :mod:`cfgplan.runtime.router`; this module reads the command
line. ``cfgplan launch`` starts one itself (its default topology); on several
hosts, start it on one of them and give every robot ``--router
tcp/THAT-HOST:7447`` (``zenohd`` or ``rmw_zenohd`` serve as well). With
``--keys DIR`` it is the society's secured router: TLS, mutual
authentication, the society's access control on every client.
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
    keys: Annotated[
        Path | None,
        typer.Option(
            "--keys",
            metavar="DIR",
            help="The society's keys with the router's own (cfgplan keys new makes it): "
            "TLS only (tcp/ endpoints become tls/), every client asked for a certificate "
            "of the society's authority, and the society's access control enforced on "
            "each, by its certificate's name.",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Run a Zenoh router (Zenoh's own, in router mode) until Ctrl-C or SIGTERM.

    Each robot started with --router ENDPOINT holds one connection, to this router,
    instead of one to every other robot. Without keys, anyone who reaches the
    router reaches the society; with --keys DIR only the society's members do, each
    held to what it may send and be sent (give the robots --keys too). Exit codes: 0
    stopped, 1 it could not open or its keys are wrong, 2 usage.
    """
    from cfgplan.runtime.router import DEFAULT_LISTEN, RouterOptions, serve

    try:
        options = RouterOptions(
            listen=tuple(listen or (DEFAULT_LISTEN,)),
            lease=DEFAULT_LEASE if lease is None else lease,
            config_file=None if zenoh_config is None else str(zenoh_config),
            keys=None if keys is None else str(keys),
        )
        serve(options, lambda line: typer.echo(line))
    except RunError as exc:
        raise run_error(exc) from None
