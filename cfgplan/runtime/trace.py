"""What a running configuration did, as lines of text (``cfgplan run``, emitted code).

Every word the console of a run prints is here (the printer,
:mod:`cfgplan.runtime.console`, only chooses which events to show, and
where): a call (:func:`describe`), any other event worth telling
(:func:`notice`: losses, stale inputs, failures and switches with their
cause), a functionality's failures on stderr (:func:`fault`, tagged with the
implementation's file, or ``[injected]`` for a scripted fault), the compact
status (:func:`status_parts`) and the summary (:func:`summary`). Nothing
here depends on timing (durations stay in the trace), so that a run's plain
console is the same from one run to the next.

Values are shown compactly and deterministically: floats with three
decimals, tuples, lists and dicts element by element, anything else by its
``repr`` — cut to a readable length, control characters escaped. A value
that contains itself shows ``...`` where it recurs; one whose ``__repr__``
raises shows a placeholder, and :func:`show` says what went wrong so the
printer can blame the implementation.
"""

from __future__ import annotations

from collections.abc import Iterable

from cfgplan.notation import call_text
from cfgplan.runtime.events import Adaptation, Call, Data, Event, Lifecycle, Presence, Staleness
from cfgplan.runtime.values import safe_repr
from cfgplan.runtime.wrapper import Stats, Wrapper

__all__ = [
    "call_text",
    "describe",
    "fault",
    "further_faults",
    "notice",
    "runs_again",
    "show",
    "show_checked",
    "status_parts",
    "summary",
    "undelivered",
    "value_warning",
    "waits",
]

DEPTH = 12  # containers shown this deep, then "..."
WIDTH = 400  # characters of one value, then "…"


def show(value: object) -> str:
    """``(1.500, -0.250)`` for a pair of floats; ``{'Door1': (...)}`` for a dict."""
    return show_checked(value)[0]


def show_checked(value: object) -> tuple[str, str | None]:
    """:func:`show`, and what was wrong with the value's ``__repr__`` if anything."""
    problems: list[str] = []
    text = _show(value, set(), 0, problems)
    if len(text) > WIDTH:
        text = text[: WIDTH - 1] + "…"
    return text, (problems[0] if problems else None)


def _show(value: object, open_ids: set[int], depth: int, problems: list[str]) -> str:
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, float):
        text = f"{value:.3f}"
        return "0.000" if text == "-0.000" else text
    if type(value) in (tuple, list, dict):
        if id(value) in open_ids or depth >= DEPTH:
            return "..."
        open_ids.add(id(value))
        try:
            return _container(value, open_ids, depth, problems)
        finally:
            open_ids.discard(id(value))
    text, problem = safe_repr(value, WIDTH)
    if problem is not None:
        problems.append(problem)
    return text


def _container(value: object, open_ids: set[int], depth: int, problems: list[str]) -> str:
    def inner(items: Iterable[object]) -> str:
        return ", ".join(_show(v, open_ids, depth + 1, problems) for v in items)

    if isinstance(value, tuple):
        return f"({inner(value)},)" if len(value) == 1 else f"({inner(value)})"
    if isinstance(value, list):
        return f"[{inner(value)}]"
    assert isinstance(value, dict)
    pairs = (
        f"{_show(k, open_ids, depth + 1, problems)}: {_show(v, open_ids, depth + 1, problems)}"
        for k, v in value.items()
    )
    return "{" + ", ".join(pairs) + "}"


def _pairs(pairs: Iterable[tuple[Data, object]], problems: list[str]) -> str:
    out = []
    for d, v in pairs:
        if v is None:
            out.append(f"{call_text(d)} = (no data)")
            continue
        text, problem = show_checked(v)
        if problem is not None:
            problems.append(f"{call_text(d)}: {problem}")
        out.append(f"{call_text(d)} = {text}")
    return ", ".join(out)


def _head(event: Call) -> str:
    return (
        f"cycle {event.cycle}: {event.robot} {event.label} {call_text((event.name, *event.args))}"
    )


def describe(event: Call, problems: list[str] | None = None) -> str:
    """One line: ``cycle 2: Pippi F3 cross-door(Pippi, Door1) received pos(...) = ...``.

    ``problems`` collects what was wrong with a value shown (a failing ``__repr__``).
    """
    found: list[str] = [] if problems is None else problems
    return f"{_head(event)} {_did(event, found)}".rstrip()


def _did(event: Call, found: list[str]) -> str:
    """What a call did, after its head: ``received ...``, ``waits for ...``."""
    if event.status == "waiting":
        return "waits for " + ", ".join(call_text(d) for d in event.waiting)
    if event.status == "stale":
        return "does not run: stale " + ", ".join(call_text(d) for d in event.stale)
    if event.status == "precondition":
        return "does not run: precondition false"
    if event.status == "busy":
        return "does not run: its last call is still running"
    if event.status in ("error", "timeout"):
        return f"failed: {event.error}"
    if event.action:
        return f"received {_pairs(event.inputs, found)}"
    parts = []
    if event.inputs:
        parts.append(f"read {_pairs(event.inputs, found)}")
    parts.append(f"wrote {_pairs(event.outputs, found)}")
    return "; ".join(parts)


def notice(event: Event) -> str | None:
    """A line for an event that is not a call, worth telling a user; else ``None``."""
    head = f"cycle {event.cycle}: {event.robot}"
    if isinstance(event, Presence):
        return f"{head}: robot {event.other} {'seen' if event.alive else 'lost'}"
    if isinstance(event, Staleness):
        if event.state == "stale":
            return (
                f"{head} {event.label}: input {call_text(event.channel.data)} from "
                f"{event.source_robot} is stale (no new data for over {event.limit:g} s)"
            )
        return f"{head} {event.label}: input {call_text(event.channel.data)} is fresh again"
    if isinstance(event, Lifecycle) and event.what == "error":
        return f"{head}: {dict(event.info).get('message', '')}"
    if isinstance(event, Adaptation):
        return adaptation(event)
    return None  # calls have describe(); sends, receives, start and stop go to the trace


def _names(value: object) -> str:
    return ", ".join(str(v) for v in value) if isinstance(value, list) and value else "none"


def _number(value: object) -> str:
    return f"{value:g}" if isinstance(value, int | float) else "-"


def _switch(event: Adaptation) -> str:
    f = event.field
    stopped, started = f("stopped"), f("started")
    assert isinstance(stopped, dict) and isinstance(started, dict)
    return (
        f"switch {f('id')} ({f('cause')}): cost {_number(f('from_cost'))} -> "
        f"{_number(f('to_cost'))} ({f('source')}); "
        f"stopped {_names(stopped['functionalities'])}; "
        f"started {_names(started['functionalities'])}"
    )


def _finish(event: Adaptation) -> str:
    """The end of a run across processes: a robot told by the coordinator, or
    the coordinator once every robot was told."""
    goal, sender, silent = event.field("goal"), event.field("from"), event.field("silent")
    if sender is not None:
        what = (
            f"the task is accomplished ({goal}, says {sender})"
            if goal
            else (f"the task is accomplished (says {sender})")
        )
        return f"{what}: the run ends"
    if isinstance(silent, list) and silent:
        return f"the run ends; no answer to the end of the run from {_names(silent)}"
    return "every robot knows the task is accomplished: the run ends"


def adaptation(event: Adaptation) -> str | None:
    """A line for a step of monitoring and reconfiguration (5.5)."""
    head = f"cycle {event.cycle}: {event.robot}"
    f = event.field
    if event.what == "inject":
        return f"{head}: injected: {f('spec')}"
    if event.what == "failure":
        withdrawn = f("withdrawn")
        gone = (
            f"; withdraws {' '.join(map(str, withdrawn))}"
            if isinstance(withdrawn, list) and withdrawn
            else ""
        )
        detail = f("detail")
        cause = f": {detail}" if detail and f("how") != "injected" else ""  # said before
        return (
            f"{head}: failure of {f('resource')} ({f('how')}, seen by {f('detected_by')})"
            f"{cause}{gone}"
        )
    if event.what == "recovery":
        return f"{head}: {f('resource')} works again ({f('how')})"
    if event.what == "facts":
        added, removed = _names(f("added")), _names(f("removed"))
        return f"{head}: state update ({f('how')}): added {added}; removed {removed}"
    if event.what == "switch":
        return f"{head}: {_switch(event)}"
    if event.what == "no-configuration":
        why = f("why")
        lines = [
            f"{head}: no admissible configuration ({f('cause')}): stopped {_names(f('stopped'))}"
        ]
        if isinstance(why, list):
            lines += [f"  {line}" for line in why]
        return "\n".join(lines)
    if event.what == "finish":
        return f"{head}: {_finish(event)}"
    if event.what == "takeover":
        said = (("added", "added"), ("removed", "removed"), ("failed", "out of service"))
        learnt = [f"{what} {_names(f(key))}" for key, what in said if f(key)]
        known = f"; the society had {', '.join(learnt)}" if learnt else ""
        return (
            f"{head}: {f('after')}, the coordinator, is gone: {event.robot} coordinates from "
            f"step {_number(f('step'))} on ({f('goal')}; run {f('epoch')}){known}"
        )
    if event.what == "step-down":
        return (
            f"{head}: {f('leader')} took over coordination (run {f('epoch')}): "
            f"{event.robot} steps down and follows it"
        )
    if event.what == "achieved":
        return (
            f"{head}: {f('functionality')} accomplished its task: the configuration is played out"
        )
    return None


def fault(event: Call, source: str) -> str:
    """A functionality's failure (stderr), tagged with what is to blame: the
    implementations' file, or ``injected`` for a scripted fault (``--inject``).
    A failure whose place is already in that file (``(impl.py:11 in localise)``)
    names it once: the tag would only repeat it."""
    text = describe(event)
    if event.failure == "injected":
        return f"cfgplan: {text} [injected]"
    if source and f"({source}:" in text:
        return f"cfgplan: {text}"
    return f"cfgplan: {text} [{source}]"


def further_faults(event: Call) -> str:
    return (
        f"cfgplan: further failures of {event.label} {event.name} on {event.robot} "
        "are only counted (summary; --trace has each)"
    )


def value_warning(event: Call, problem: str, source: str) -> str:
    """A value whose ``__repr__`` fails, blaming the implementation (stderr)."""
    return (
        f"cfgplan: warning: {event.label} {event.name} on {event.robot}: {problem} "
        f"(implementations: {source})"
    )


def waits(event: Call, calls: int) -> str:
    """A functionality has waited ``calls`` calls in a row for its data."""
    return f"{describe(event)} ({calls} calls in a row so far)"


def runs_again(event: Call) -> str:
    return f"{_head(event)} runs again"


def undelivered(count: int) -> str:
    return (
        f"note: {count} value(s) sent to robots not in this process were dropped "
        "(the in-process transport joins only robots run together)"
    )


def status_parts(
    cycles: dict[str, int],
    actions: Iterable[tuple[Call, int]],
    counts: dict[str, int],
    cost: object = None,
) -> list[str]:
    """The compact status of a run, piece by piece: each robot's cycles;
    switches (and the cost now), failures, stale inputs, robots lost and
    errors (messages dropped), when any; each action, how often it ran and
    what it last received (or why not)."""
    parts = ["cycles " + ", ".join(f"{robot} {n}" for robot, n in cycles.items())]
    switches = counts.get("switch", 0)
    if switches:
        now = f", now cost {_number(cost)}" if cost is not None else ""
        parts.append(f"{switches} switch{'es' if switches > 1 else ''}{now}")
    for key, one, many in (
        ("failure", "failure", "failures"),
        ("stale", "stale input", "stale inputs"),
        ("lost", "robot lost", "robots lost"),
        ("error", "error", "errors"),
    ):
        n = counts.get(key, 0)
        if n:
            parts.append(f"{n} {one if n == 1 else many}")
    for last, ran in actions:  # last: the longest
        shown = call_text((last.name, *last.args))
        now = "last " if last.status == "ran" else "now "
        parts.append(f"{shown} ran {ran} times, {now}{_did(last, [])}".rstrip())
    return parts


def summary(wrappers: Iterable[Wrapper]) -> list[str]:
    """Per functionality, in the order given: how often it ran, and what kept it from running."""
    return [_line(w, w.stats) for w in wrappers if w.stats.calls]


def _line(w: Wrapper, stats: Stats) -> str:
    ran = stats.by_status.get("ran", 0)
    line = f"{w.robot} {w.label} {call_text((w.name, w.robot, *w.objects))}: "
    line += f"ran in {ran} of {stats.calls} cycles"
    last = stats.last
    if ran == 0 and last is not None and last.status == "waiting":
        line += "; waits for " + ", ".join(call_text(d) for d in last.waiting)
    elif ran == 0 and last is not None and last.status == "precondition":
        line += "; precondition false"
    for status, what in (("stale", "refused stale input"), ("timeout", "timed out")):
        n = stats.by_status.get(status, 0)
        if n:
            line += f"; {what} {n} time{'s' if n > 1 else ''}"
    failed = stats.by_status.get("error", 0)
    if failed:
        line += f"; failed {failed} time{'s' if failed > 1 else ''}, last: {stats.last_error}"
    if w.stopped:
        line += "; stopped"
    return line
