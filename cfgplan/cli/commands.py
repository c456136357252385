"""Importing this module registers every command on the typer app, :data:`cfgplan.cli.root.app`."""

from cfgplan.cli import check, emit, keys, plan, record, render, run, simulate

__all__ = ["check", "emit", "keys", "plan", "record", "render", "run", "simulate"]
