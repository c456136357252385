"""Importing this module registers every command on the typer app, :data:`cfgplan.cli.root.app`."""

from cfgplan.cli import check, emit, keys, launch, plan, record, render, report, run, simulate

__all__ = [
    "check",
    "emit",
    "keys",
    "launch",
    "plan",
    "record",
    "render",
    "report",
    "run",
    "simulate",
]
