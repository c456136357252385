"""The configuration planner of thesis 4.5.

The pipeline reads off the module names: ``task`` (the domain and state
compiled) and ``costs`` (what each part costs, and how costs rank),
``unify`` and ``ground`` (preconditions against the state, instances made on
demand), ``graph`` (the AND/OR graph of ground instances), ``partial`` (the
node, its channels, and the two steps that grow it), ``bound`` and
``partition`` (the two lower bounds), ``pricer`` (a node's priority by them,
and when the dearer one is worth it), ``grow`` (one step of 4.5, replays, and
what every strategy does to a node), ``search`` (the tie order, best-first,
``--all`` in bounded memory, the anytime dive, ``-k N`` and one more),
``combine`` (a goal's independent parts, searched apart and combined),
``solver`` (the answer-set solver and its race with the search), ``clock``
(the time limit), ``options`` (the search's settings), ``finish`` (step 4:
admissibility), ``report`` and ``explain`` (why nothing was found, and how a
run ended), ``sequence`` (several goals), and ``plan``, the entry point.

The entry point (``plan``, ``Run``, ``Stats``) is imported when first asked
for: reading, checking and compiling a problem (:mod:`cfgplan.problem`) use
the task and its compiler, and a robot that follows its coordinator
(``cfgplan run --robot``, :mod:`cfgplan.reconfigure.owner`) plans nothing,
so the search's modules are not loaded for them. ``plan`` is also the name of
the entry point's module: the package's ``plan`` is the function whichever
was imported first (:class:`_Planner`).
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cfgplan.planner.plan import Run, plan
    from cfgplan.planner.report import Stats

__all__ = ["Run", "Stats", "plan"]


def __getattr__(name: str) -> object:
    """``Run``, ``Stats`` and ``plan``, imported on first use."""
    if name in ("Run", "plan"):
        return getattr(importlib.import_module(f"{__name__}.plan"), name)
    if name == "Stats":
        return importlib.import_module(f"{__name__}.report").Stats
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class _Planner(types.ModuleType):
    """The package, whose ``plan`` stays the entry point: importing the
    submodule :mod:`cfgplan.planner.plan` sets the package's attribute of its
    name to the module, and it is replaced by the function it defines."""

    def __setattr__(self, name: str, value: object) -> None:
        if isinstance(value, types.ModuleType) and value.__name__ == f"{__name__}.plan":
            value = value.plan
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Planner
