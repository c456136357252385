"""The static checker: mistakes in a domain, state and goal found before planning.

:func:`check` returns :class:`~cfgplan.diagnostics.Diagnostic` objects sorted by
file position. It covers the well-formedness the thesis takes for granted:
functionalities with inputs or outputs (3.2), calls that resolve by name and
arity (4.4, 4.5), channels and ``:in``/``:out`` ports between body labels whose
callees produce or consume the data (3.4, 4.4, 4.5 step d), bound variables,
and ``(eval ...)`` tests inside the safe subset (Appendix A); the state and
goal are checked against the domain by :mod:`cfgplan.check.state`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from cfgplan.check import evaluate
from cfgplan.check.findings import Findings
from cfgplan.check.messages import (
    alternatives,
    position,
    sig_text,
    where,
)
from cfgplan.check.state import check_goal, check_state
from cfgplan.check.unify import Signature, caller_equations, instantiate, match
from cfgplan.diagnostics import Diagnostic
from cfgplan.ir.model import (
    Atom,
    BodyItem,
    ChannelSpec,
    Condition,
    Domain,
    Eval,
    Functionality,
    Goal,
    Method,
    Negation,
    Port,
    Span,
    State,
    Term,
)

Side = Literal["out", "in"]


def check(domain: Domain, state: State | None = None, goal: Goal | None = None) -> list[Diagnostic]:
    """All errors and warnings about ``domain`` (and ``state``, ``goal``), by file position.

    ``goal`` defaults to ``state.goal`` (or every goal of ``state.sequence``).
    An empty list, or warnings only, means
    the planner may run.
    """
    checker = _Checker(domain)
    checker.definitions()
    for functionality in domain.functionalities:
        checker.functionality(functionality)
    for method in domain.methods:
        checker.method(method)
    if state is not None:
        check_state(checker, state)
    targets = [goal] if goal is not None else []
    if goal is None and state is not None:
        targets = [state.goal] if state.goal is not None else list(state.sequence)
    for target in targets:
        check_goal(checker, target, state)
    return checker.sorted()


class _Checker(Findings):
    """The checks of one domain's definitions, functionalities and methods."""

    # -- names -----------------------------------------------------------

    def definitions(self) -> None:
        """Duplicate functionalities; names that are a functionality and a method (4.4)."""
        first: dict[Signature, Functionality] = {}
        for f in self.domain.functionalities:
            sig = f.name.signature
            if sig in first:
                at = where(first[sig].span, f.span)
                self.report(
                    "error",
                    f"functionality {sig_text(sig)} is defined twice; the first is at {at}",
                    f.name.span,
                    "a functionality is identified by name and arity; rename or remove one",
                )
            else:
                first[sig] = f
        for sig, f in first.items():
            if sig not in self.versions:
                continue
            m = self.versions[sig][0]
            later, earlier = (m, f) if position(m.span) >= position(f.span) else (f, m)
            kind = "method" if later is m else "functionality"
            self.report(
                "error",
                f"{sig_text(sig)} is both a functionality and a method; "
                f"this {kind} clashes with the one at {where(earlier.span, later.span)}",
                later.name.span,
                "a body entry must name either a functionality or a method (4.4)",
            )

    # -- functionalities -------------------------------------------------

    def functionality(self, f: Functionality) -> None:
        """A functionality needs :in or :out (3.2) and names the variables it uses."""
        if not f.inputs and not f.outputs:
            self.report(
                "error",
                f"functionality {f.name} has neither :in nor :out",
                f.span,
                "a sensing resource has :out, an action resource :in, "
                "a processing functionality both (3.2)",
            )
        # A call binds the name's variables; its preconditions' atoms may bind
        # more (4.5: the outputs of (loc ?r) with (in ?r ?room) name the room).
        named = set(f.name.variables())
        named.update(v for c in f.precond if isinstance(c, Atom) for v in c.variables())
        for d in (*f.inputs, *f.outputs):
            for v in dict.fromkeys(d.variables()):
                if v not in named:
                    self.report(
                        "warning",
                        f"{v} in {d} occurs neither in the name {f.name} nor in a precondition",
                        d.span,
                        "a call binds the variables of the name; its preconditions may bind more",
                    )
        self._conditions(f.name, f.precond)

    # -- methods ---------------------------------------------------------

    def method(self, m: Method) -> None:
        """Body calls, labels, channels, ports, variables and tests of a method (4.4)."""
        if not m.body:
            self.report(
                "error",
                f"method {m.name} has an empty :body",
                m.span,
                "a method expands into functionality or method calls (4.4)",
            )
        labels: dict[str, BodyItem] = {}
        for item in m.body:
            if item.label in labels:
                at = where(labels[item.label].span, item.span)
                self.report(
                    "error",
                    f"body label {item.label} is used twice in {m.name}; the first is at {at}",
                    item.span,
                )
            else:
                labels[item.label] = item
            self._call(item)
        known = ", ".join(labels) or "none"
        for ch in m.channels:
            ends: list[tuple[str, str, Side]] = [
                (ch.source, "source", "out"),
                (ch.target, "target", "in"),
            ]
            for label, role, side in ends:
                if label not in labels:
                    self.report(
                        "error",
                        f"channel {role} {label} is not a label of the body of {m.name}",
                        ch.span,
                        f"body labels: {known}",
                    )
                else:
                    self._flow(labels[label], ch.data, side, "channel data", ch.span)
            self._channel_robots(ch, labels)
        sides: list[tuple[Side, tuple[Port, ...]]] = [("in", m.inputs), ("out", m.outputs)]
        for side, ports in sides:
            for port in ports:
                if port.label not in labels:
                    self.report(
                        "error",
                        f":{side} label {port.label} is not a label of the body of {m.name}",
                        port.span,
                        f"body labels: {known}",
                    )
                else:
                    self._flow(labels[port.label], port.data, side, f":{side} data", port.span)
        seen: dict[tuple[str, tuple[Term, ...]], Span | None] = {}
        for port in m.outputs:
            key = (port.data.predicate, port.data.args)
            if key in seen:
                self.report(
                    "error",
                    f"two :out ports give {port.data}; the first is at "
                    f"{where(seen[key], port.span)}",
                    port.span,
                    "a channel to this method could not be re-wired unambiguously (4.5)",
                )
            else:
                seen[key] = port.span
        self._method_variables(m)
        self._conditions(m.name, m.precond)

    def _channel_robots(self, ch: ChannelSpec, labels: dict[str, BodyItem]) -> None:
        """``((global ?from ?to) ?f1 ?f2 ...)`` whose robots are written the other
        way round: ?f1 a functionality on ?to, ?f2 one on ?from (a functionality
        runs on its first argument, 3.2). The planner finds no placement for it
        and drops the method's configurations without a word."""
        if ch.kind == "local" or len(ch.robots) != 2 or ch.robots[0] == ch.robots[1]:
            return
        ends = [labels.get(ch.source), labels.get(ch.target)]
        on = [
            e.call.args[0]
            if e is not None and e.call.signature in self.funcs and e.call.args
            else None
            for e in ends
        ]
        first, second = ch.robots
        if on == [second, first]:
            self.report(
                "warning",
                f"the channel {ch.source} -> {ch.target} is ({ch.kind} {first} {second}), but "
                f"{ch.source} runs on {second} and {ch.target} on {first}",
                ch.span,
                f"the robots are the source's, then the target's: did you mean "
                f"({ch.kind} {second} {first})?",
            )

    def _call(self, item: BodyItem) -> None:
        """A body entry names a functionality or method by name and arity (4.5)."""
        call = item.call
        if call.signature in self.funcs or call.signature in self.versions:
            return
        arities = [s[1] for s in (*self.funcs, *self.versions) if s[0] == call.predicate]
        if arities:
            self.report(
                "error",
                f"arity mismatch: ({call.predicate} ...) takes {alternatives(arities)}, "
                f"found {call.arity}",
                call.span,
                "a functionality or method is identified by its name and arity",
            )
            return
        self.report(
            "error",
            f"{item.label} calls {call}, but no functionality or method "
            f"{sig_text(call.signature)} is defined",
            call.span,
            self.did_you_mean(call.predicate),
        )

    def _offers(self, call: Atom, side: Side) -> list[tuple[Atom, Atom]] | None:
        """(schema name, descriptor) pairs the callee produces or consumes; None if undefined."""
        pairs: list[tuple[Atom, Atom]] = []
        defined = False
        f = self.funcs.get(call.signature)
        if f is not None:
            defined = True
            pairs += [(f.name, d) for d in (f.outputs if side == "out" else f.inputs)]
        for m in self.versions.get(call.signature, []):
            defined = True
            pairs += [(m.name, p.data) for p in (m.outputs if side == "out" else m.inputs)]
        return pairs if defined else None

    def _flow(self, item: BodyItem, data: Atom, side: Side, what: str, span: Span | None) -> None:
        """The callee of ``item`` produces (``out``) or consumes (``in``) ``data`` (4.5 step d).

        A descriptor that unifies only by equating the caller's own terms (``?rh1``
        with ``?r``) gets a warning: it holds only for some bindings.
        """
        offers = self._offers(item.call, side)
        if offers is None:
            return
        verb = "produce" if side == "out" else "consume"
        loose: list[tuple[Atom, list[tuple[Term, Term]]]] = []
        for name, descriptor in offers:
            subst = match(name, item.call, descriptor, data)
            if subst is None:
                continue
            equations = caller_equations(subst)
            if not equations:
                return
            loose.append((instantiate(name, item.call, descriptor), equations))
        if loose:
            shown, equations = loose[0]
            demands = " and ".join(f"{a} = {b}" for a, b in equations)
            self.report(
                "warning",
                f"{what} {data} is {verb}d by {item.label} {item.call} only if {demands}",
                span,
                f"it {verb}s {shown}; check the variables of both",
            )
            return
        shown_all = list(dict.fromkeys(str(instantiate(n, item.call, d)) for n, d in offers))
        hint = f"it {verb}s " + (", ".join(shown_all) if shown_all else "nothing")
        if self.versions.get(item.call.signature):
            port = ":out" if side == "out" else ":in"
            hint += f" (the {port} ports of its method versions)"
        self.report(
            "error", f"{what} {data} is not {verb}d by {item.label} {item.call}", span, hint
        )

    def _method_variables(self, m: Method) -> None:
        """Variables of channels, ports and calls are bound by the name or a
        precondition: one bound by nothing leaves the call, channel or port
        unground, and every expansion of the method fails (4.5, step 3a)."""
        bound = set(m.name.variables())
        for cond in m.precond:
            if isinstance(cond, Atom):
                bound |= set(cond.variables())
        uses: list[tuple[Sequence[Term], Span | None]] = []
        uses += [((*ch.robots, *ch.data.args), ch.span) for ch in m.channels]
        uses += [(p.data.args, p.span) for p in (*m.inputs, *m.outputs)]
        uses += [(item.call.args, item.call.span) for item in m.body]
        first: dict[Term, Span | None] = {}
        for terms, span in uses:
            for t in terms:
                new = t not in first or position(span) < position(first[t])
                if t.startswith("?") and t not in bound and new:
                    first[t] = span
        for v, span in first.items():
            self.report(
                "error",
                f"{v} is bound by neither the name nor a precondition of {m.name}, "
                "so no expansion of it can be made",
                span,
                f"add {v} to the name or bind it with a precondition such as (robot {v})",
            )

    def _conditions(self, name: Atom, precond: Sequence[Condition]) -> None:
        """Evals stay in the safe subset; evals and negations use bound variables only."""
        bound = set(name.variables())
        for cond in precond:
            if isinstance(cond, Atom):
                bound |= set(cond.variables())
        for cond in precond:
            if isinstance(cond, Eval):
                for problem in evaluate.problems(cond.expr):
                    self.report(
                        "error",
                        problem,
                        cond.span,
                        "(eval ...) is interpreted in a safe subset, never executed (Appendix A)",
                    )
                used = cond.variables()
            elif isinstance(cond, Negation):
                used = cond.atom.variables()
            else:
                continue
            for v in dict.fromkeys(used):
                if v not in bound:
                    self.report(
                        "error",
                        f"{v} in {cond} is bound by neither the name nor an atom "
                        "precondition, so it can never be bound",
                        cond.span,
                        f"bind {v} with an atom precondition of {name}",
                    )
