"""Importing this module registers every command on :data:`cfgplan.cli.app.app`."""

from cfgplan.cli import check, emit, plan, render, run, simulate

__all__ = ["check", "emit", "plan", "render", "run", "simulate"]
