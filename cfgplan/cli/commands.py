"""Every command module, imported: for a program or a test that wants them all
loaded at once (the root group loads a command as it is asked for,
:mod:`cfgplan.cli.registry`; importing a command module registers nothing)."""

import importlib

from cfgplan.cli.registry import COMMANDS, module_of

for _name in COMMANDS:
    importlib.import_module(module_of(_name))
