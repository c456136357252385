"""Importing this module registers every command on the typer app,
:data:`cfgplan.cli.root.app`: it imports the module of each command named in
:data:`cfgplan.cli.app.COMMANDS`, the one list of them (a command line that
names one loads that one only, :func:`cfgplan.cli.app.register`)."""

import importlib

from cfgplan.cli.app import COMMANDS

for _name in COMMANDS:
    importlib.import_module(f"cfgplan.cli.{_name}")
