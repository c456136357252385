"""How ``cfgplan plan`` prints configurations for one goal (thesis 4.4, 4.6).

``table`` for people (rich), ``lisp`` the thesis's configuration
descriptions, ``json`` one document and ``jsonl`` one configuration a line
then a summary line (the schema: README, "Output formats"). Every format
numbers the configurations by rank from ``first`` (``--rank N`` shows the
N-th alone). Names from the input are shown with control characters escaped.
"""

from __future__ import annotations

import io
import json
import shutil

from rich.console import Console
from rich.table import Table

from cfgplan.configuration.cost import fmt
from cfgplan.configuration.describe import channel_text, to_dict, to_text
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import printable
from cfgplan.notation import call_text
from cfgplan.planner import Run
from cfgplan.problem import Problem

__all__ = ["lisp", "stats", "streamed", "summary", "table"]

NO_MEDIA = "the state declares no media: communication admissibility not checked"


def stats(search: Run, more: bool = False) -> dict[str, object]:
    s = search.stats
    return {
        "more": more,
        "nodes": s.nodes,
        "expansions": s.expansions,
        "derivations": s.derivations,
        "duplicates": s.duplicates,
        "rejected": s.rejected,
        "exhausted": s.complete,
        "stopped": search.stopped.value if search.stopped else None,
    }


def table(
    problem: Problem, configs: list[Configuration], details: bool, more: bool, first: int = 1
) -> str:
    """The table for people: names with control characters escaped (a name
    holding ESC cannot drive the terminal)."""
    shown = Table(title=printable(f"Configurations for {call_text(problem.goal_call)}"))
    shown.add_column("rank", justify="right")
    shown.add_column("cost", justify="right")
    shown.add_column("robots")
    devices = any(c.devices for c in configs)
    if devices:
        shown.add_column("devices")
    shown.add_column("functionalities", justify="right")
    shown.add_column("local", justify="right")
    shown.add_column("global", justify="right")
    if details:
        shown.add_column("functionality instances")
        shown.add_column("channels")
    for rank, c in enumerate(configs, first):
        row = [
            str(rank),
            fmt(c.cost) + ("" if c.proven else " *"),
            ", ".join(c.robots),
            *([", ".join(c.devices)] if devices else []),
            str(len(c.functionalities)),
            str(c.local_channels),
            str(c.global_channels),
        ]
        if details:
            row.append("\n".join(str(f) for f in c.functionalities))
            row.append("\n".join(channel_text(ch) for ch in c.channels))
        shown.add_row(*(printable(cell, keep="\n") for cell in row))
    buffer = io.StringIO()
    # With --details the table is as wide as the terminal (200 when not one).
    width = shutil.get_terminal_size((200, 24)).columns if details else 100
    Console(file=buffer, width=width, force_terminal=False, color_system=None).print(shown)
    if more:
        wider = len(configs) + 10
        buffer.write(f"note: more configurations exist: --all lists them all, -k {wider} more\n")
    if not problem.state.media:
        buffer.write(f"note: {NO_MEDIA}\n")
    if any(not c.proven for c in configs):
        buffer.write("* not proven optimal: the search was stopped before it could prove it\n")
    return buffer.getvalue()


def streamed(problem: Problem, config: Configuration, rank: int, format_: str) -> str:
    """One configuration as ``--format jsonl`` or ``lisp`` prints it, alone."""
    if format_ == "jsonl":
        line = to_dict(config, rank, problem.state.media)
        return json.dumps(line, ensure_ascii=False) + "\n"
    head = ""
    if rank == 1:
        head = f";; cfgplan: configurations for {call_text(problem.goal_call)}\n"
        if not problem.state.media:
            head += f";; {NO_MEDIA}\n"
    shown = f";; rank {rank}" + ("" if config.proven else ", not proven optimal")
    return head + shown + "\n" + to_text(config, problem.state.media) + "\n"


def summary(
    problem: Problem,
    configs: list[Configuration],
    search: Run,
    more: bool = False,
    explained: dict[str, object] | None = None,
) -> str:
    """The last line of ``--format jsonl``: what was planned for, and how."""
    doc: dict[str, object] = {
        "goal": call_text(problem.goal_call),
        "count": len(configs),
        "communication_checked": bool(problem.state.media),
        "stats": stats(search, more),
    }
    if explained is not None:
        doc["explanation"] = explained
    return json.dumps(doc, ensure_ascii=False) + "\n"


def lisp(problem: Problem, configs: list[Configuration], first: int = 1) -> str:
    parts = [f";; cfgplan: {len(configs)} configuration(s) for {call_text(problem.goal_call)}"]
    if not problem.state.media:
        parts.append(f";; {NO_MEDIA}")
    for rank, c in enumerate(configs, first):
        parts.append(f";; rank {rank}" + ("" if c.proven else ", not proven optimal"))
        parts.append(to_text(c, problem.state.media))
    return "\n".join(parts) + "\n"
