"""The configuration planner of thesis 4.5.

The pipeline reads off the module names: ``task`` (the domain and state
compiled), ``unify`` and ``match`` (preconditions against the state),
``ground`` (instances made on demand), ``partial`` (the node and the two
steps that grow it), ``successors`` (one step of 4.5), ``bound`` and
``partition`` (the heuristics), ``pricer`` (a node's priority by them, and
when the dearer one is worth it), ``grow`` (what every strategy does to a
node), ``search`` (best-first), ``components`` and ``combine`` (a goal's
independent parts, searched apart and combined) and ``enumerate`` (every
configuration, in bounded memory), ``dive`` (an anytime answer), ``clock`` (the time limit),
``finish`` (step 4: admissibility), ``report`` and ``explain`` (why nothing
was found), and ``plan``, the entry point.

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
