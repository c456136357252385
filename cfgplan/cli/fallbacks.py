"""``cfgplan plan --fallbacks``: the robustness report of the chosen configuration (5.5, 7.2).

For each resource the cheapest configuration uses (functionality instance,
robot or device, medium), the best configuration if that resource fails, or
"none": the single points of failure. As a table after the configurations,
as comment lines in the ``lisp`` format, and as ``"fallbacks"`` in JSON
(:meth:`cfgplan.reconfigure.fallbacks.Fallback.record`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cfgplan.cli.formats import plain
from cfgplan.configuration.cost import fmt
from cfgplan.configuration.model import Configuration
from cfgplan.notation import atom_text

if TYPE_CHECKING:  # the reconfiguration is loaded only for --fallbacks (start-up)
    from cfgplan.reconfigure.fallbacks import Fallback

__all__ = ["fallback_lisp", "fallback_table"]


def _withdrawn(fb: Fallback) -> str:
    return " ".join(atom_text(f) for f in fb.withdrawn) or "-"


def _switch(fb: Fallback) -> str:
    if fb.change is None:
        return "-"
    return f"stop {len(fb.change.stopped)}, start {len(fb.change.started)}"


def _single_points(found: list[Fallback]) -> str:
    names = [fb.resource.text for fb in found if fb.config is None]
    if not names:
        return "no single point of failure: every resource has a fallback\n"
    return f"single points of failure ({len(names)}): {', '.join(names)}\n"


def fallback_table(config: Configuration, found: list[Fallback], rank: int = 1) -> str:
    """The report on ``config`` (of ``rank``) as a table, then the single points of failure."""
    from rich.table import Table  # loaded for tables only (start-up)

    title = f"Fallbacks of rank {rank} (cost {fmt(config.cost)}): if one resource fails"
    table = Table(title=title)
    table.add_column("resource", overflow="fold")
    table.add_column("kind")
    table.add_column("withdraws", overflow="fold")
    table.add_column("fallback cost", justify="right")
    table.add_column("robots")
    table.add_column("switch")
    for fb in found:
        c = fb.config
        table.add_row(
            fb.resource.text,
            fb.resource.kind,
            _withdrawn(fb),
            ("none" if c is None else fmt(c.cost)) + ("" if fb.proven else " *"),
            "-" if c is None else ", ".join([*c.robots, *c.devices]),
            _switch(fb),
        )
    text = plain(table, 150) + _single_points(found)
    if not all(fb.proven for fb in found):
        text += "* not proven: the time limit cut that search\n"
    return text


def fallback_lisp(config: Configuration, found: list[Fallback], rank: int = 1) -> str:
    """The report as ``;;`` comment lines (the ``lisp`` format stays readable by Lisp)."""
    lines = [f";; fallbacks of rank {rank} (cost {fmt(config.cost)}): if one resource fails"]
    for fb in found:
        target = "none" if fb.config is None else f"cost {fmt(fb.config.cost)}"
        lines.append(
            f";;   {fb.resource.kind} {fb.resource.text}: {target}"
            f" (withdraws {_withdrawn(fb)}; {_switch(fb)})"
        )
    lines.append(";; " + _single_points(found).rstrip("\n"))
    return "\n".join(lines) + "\n"
