"""How ``cfgplan plan`` prints configurations for one goal (thesis 4.4, 4.6).

``table`` for people (rich), ``lisp`` the thesis's configuration
descriptions, ``json`` one document and ``jsonl`` one configuration a line
then a summary line (the schema: :mod:`cfgplan.configuration.schema`). Every format
numbers the configurations by rank from ``first`` (``--rank N`` shows the
N-th alone). Names from the input are shown with control characters escaped.
"""

from __future__ import annotations

import io
import shutil
from typing import TYPE_CHECKING

from cfgplan.configuration.cost import fmt
from cfgplan.configuration.model import Configuration
from cfgplan.diagnostics import printable
from cfgplan.notation import call_text
from cfgplan.planner import Run
from cfgplan.problem import Problem

if TYPE_CHECKING:  # rich is loaded for tables only, json and the descriptions
    # (cfgplan.configuration.describe) for the other formats only (start-up)
    from rich.table import Table

__all__ = ["jsonl", "lisp", "more_note", "plain", "stats", "streamed", "summary", "table"]

NO_MEDIA = "the state declares no media: communication admissibility not checked"


def more_note(listed: int, what: str = "configuration", more: bool | None = True) -> str:
    """What the table says when ``-k`` cut the list: ``-k N`` looks for one
    configuration (or sequence, ``what``) more than it lists, so that one more
    is known to exist, never how many (counting them would mean searching to
    the end); ``more`` None: the look-ahead's work ran out before it knew."""
    wider = listed + 10
    if more is None:
        return (
            f"note: more {what}s may exist (the search for one more stopped early): "
            f"-k {wider} searches for up to {wider}, --all for them all\n"
        )
    return (
        f"note: at least one more {what} exists: "
        f"-k {wider} lists up to {wider}, --all lists them all\n"
    )


def stats(search: Run, more: bool | None = False) -> dict[str, object]:
    s = search.stats
    return {
        "more": more,
        "engine": search.engine.value,
        "nodes": s.nodes,
        "expansions": s.expansions,
        "derivations": s.derivations,
        "duplicates": s.duplicates,
        "rejected": s.rejected,
        "exhausted": search.status.exhausted,
        "stopped": search.status.value if search.status.stopped else None,
    }


def plain(shown: Table, width: int) -> str:
    """A rich table as text ``width`` columns wide, without colour or styles;
    every cell and the title as written, neither rich markup nor emoji codes
    read in them (a name ``[b]x`` or ``x:smile:`` prints as itself), which
    also spares loading rich's table of emoji (start-up)."""
    from rich.console import Console

    buffer = io.StringIO()
    console = Console(
        file=buffer, width=width, force_terminal=False, color_system=None, markup=False, emoji=False
    )
    console.print(shown)
    return buffer.getvalue()


def table(
    problem: Problem,
    configs: list[Configuration],
    details: bool,
    more: bool | None,
    first: int = 1,
) -> str:
    """The table for people: names with control characters escaped (a name
    holding ESC cannot drive the terminal)."""
    from rich.table import Table  # loaded for tables only (start-up)

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
            from cfgplan.configuration.describe import channel_text

            row.append("\n".join(str(f) for f in c.functionalities))
            row.append("\n".join(channel_text(ch) for ch in c.channels))
        shown.add_row(*(printable(cell, keep="\n") for cell in row))
    # With --details the table is as wide as the terminal (200 when not one).
    width = shutil.get_terminal_size((200, 24)).columns if details else 100
    text = plain(shown, width)
    if more or more is None:
        text += more_note(len(configs), more=more)
    if not problem.state.media:
        text += f"note: {NO_MEDIA}\n"
    if any(not c.proven for c in configs):
        text += "* not proven optimal: the search was stopped before it could prove it\n"
    return text


def streamed(
    problem: Problem, config: Configuration, rank: int, format_: str, first: int = 1
) -> str:
    """One configuration as ``--format jsonl`` or ``lisp`` prints it, alone;
    the first one shown (rank ``first``) under the LISP header. Printed as
    soon as it is proven or all at once, the bytes are the same."""
    import json

    from cfgplan.configuration.describe import to_dict, to_text

    if format_ == "jsonl":
        line = to_dict(config, rank, problem.state.media)
        return json.dumps(line, ensure_ascii=False) + "\n"
    head = _lisp_head(problem) if rank == first else ""
    shown = f";; rank {rank}" + ("" if config.proven else ", not proven optimal")
    return head + shown + "\n" + to_text(config, problem.state.media) + "\n"


def _lisp_head(problem: Problem) -> str:
    """The header of ``--format lisp``: it names no count, which is not known
    while the configurations are printed as they are proven."""
    head = f";; cfgplan: configurations for {call_text(problem.goal_call)}\n"
    if not problem.state.media:
        head += f";; {NO_MEDIA}\n"
    return head


def summary(
    problem: Problem,
    configs: list[Configuration],
    search: Run,
    more: bool | None = False,
    explained: dict[str, object] | None = None,
) -> str:
    """The last line of ``--format jsonl``: what was planned for, and how."""
    import json

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
    """The thesis's configuration descriptions (4.6), ranked from ``first``:
    byte for byte what :func:`streamed` prints one at a time."""
    if not configs:
        return _lisp_head(problem)
    shown = enumerate(configs, first)
    return "".join(streamed(problem, c, rank, "lisp", first) for rank, c in shown)


def jsonl(
    problem: Problem,
    configs: list[Configuration],
    search: Run,
    more: bool | None,
    first: int = 1,
) -> str:
    """One configuration a line, ranked from ``first``, then the summary line:
    byte for byte what :func:`streamed` and :func:`summary` print."""
    shown = enumerate(configs, first)
    lines = "".join(streamed(problem, c, rank, "jsonl") for rank, c in shown)
    return lines + summary(problem, configs, search, more)
