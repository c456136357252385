"""The static checker: mistakes in a domain, state and goal found before planning.

:func:`check` returns :class:`~cfgplan.diagnostics.Diagnostic` objects sorted by
file position. It covers the well-formedness the thesis takes for granted:
functionalities with inputs or outputs (3.2), calls that resolve by name and
arity (4.4, 4.5), channels and ``:in``/``:out`` ports between body labels whose
callees produce or consume the data (3.4, 4.4, 4.5 step d), bound variables,
and ``(eval ...)`` tests inside the safe subset (Appendix A).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Sequence
from typing import Literal

from cfgplan.check import evaluate
from cfgplan.check.messages import (
    alternatives,
    by_position,
    case_hint,
    position,
    sig_text,
    where,
)
from cfgplan.check.unify import Signature, caller_equations, instantiate, match
from cfgplan.diagnostics import Diagnostic, Severity
from cfgplan.ir.model import (
    Atom,
    BodyItem,
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
        checker.state(state)
    if goal is not None:
        checker.goal(goal)
    elif state is not None:
        for target in (state.goal,) if state.goal is not None else state.sequence:
            checker.goal(target)
    return checker.sorted()


class _Checker:
    """Collects diagnostics while walking one domain (and state, goal)."""

    def __init__(self, domain: Domain) -> None:
        self.domain = domain
        self.found: list[Diagnostic] = []
        self.funcs: dict[Signature, Functionality] = {}
        self.versions: dict[Signature, list[Method]] = {}
        for f in domain.functionalities:
            self.funcs.setdefault(f.name.signature, f)
        for m in domain.methods:
            self.versions.setdefault(m.name.signature, []).append(m)

    # -- collecting ------------------------------------------------------

    def report(
        self, severity: Severity, message: str, span: Span | None, hint: str | None = None
    ) -> None:
        self.found.append(Diagnostic(severity, message, span, hint))

    def sorted(self) -> list[Diagnostic]:
        """The domain's file first, then the state's (and the goal's)."""
        spans = [self.domain.span, *(x.span for x in self.domain.functionalities)]
        spans += [m.span for m in self.domain.methods]
        return by_position(self.found, [s.file for s in spans if s is not None])

    # -- names -----------------------------------------------------------

    def _case_hint(self, name: str, methods_only: bool = False) -> str | None:
        names = [sig[0] for sig in self.versions]
        if not methods_only:
            names += [sig[0] for sig in self.funcs]
        return case_hint(name, names)

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
            self._case_hint(call.predicate),
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

    # -- state and goal --------------------------------------------------

    def _tested(self) -> dict[str, Atom]:
        tested: dict[str, Atom] = {}
        conds = [c for f in self.domain.functionalities for c in f.precond]
        conds += [c for m in self.domain.methods for c in m.precond]
        for cond in conds:
            atom = cond.atom if isinstance(cond, Negation) else cond
            if isinstance(atom, Atom):
                tested.setdefault(atom.predicate, atom)
        return tested

    def state(self, state: State) -> None:
        """Facts no precondition tests whose predicate is close to one that is
        (a typo: ``(lazer Robby)``), and preconditions whose predicate the state
        writes only in another case (4.4)."""
        tested = self._tested()
        stated: dict[str, Atom] = {}
        for fact in state.facts:
            stated.setdefault(fact.predicate, fact)
        for pred, fact in stated.items():
            if pred in tested or pred in PLANNER_FACTS:
                continue
            hint = _did_you_mean(pred, tested)
            if hint is not None:
                self.report(
                    "warning",
                    f"no precondition tests ({pred} ...), so the fact {fact} is never used",
                    fact.span,
                    hint,
                )
        for pred, atom in tested.items():
            close = sorted(s for s in stated if s != pred and s.lower() == pred.lower())
            if pred not in stated and close:
                self.report(
                    "warning",
                    f"the state has no ({pred} ...) fact for the precondition {atom}",
                    atom.span,
                    f"symbols are case-sensitive: the state writes {' and '.join(close)}",
                )

    def goal(self, goal: Goal) -> None:
        """The goal names a method by name and arity (4.5)."""
        call = goal.call
        if call.signature in self.versions:
            return
        span = call.span or goal.span
        if call.signature in self.funcs:
            self.report(
                "error",
                f"the goal {call} names a functionality, not a method",
                span,
                "a goal is a method instance such as (do-cross-door Pippi Door1)",
            )
            return
        arities = [s[1] for s in self.versions if s[0] == call.predicate]
        hint = _did_you_mean(call.predicate, {s[0] for s in self.versions})
        if arities:
            hint = f"({call.predicate} ...) takes {alternatives(arities)}, found {call.arity}"
        self.report(
            "error",
            f"the goal {call} names no method {sig_text(call.signature)}",
            span,
            hint,
        )


PLANNER_FACTS = frozenset({"device"})
"""Fact predicates the planner itself reads (:mod:`cfgplan.configuration.cost`):
used even when no precondition tests them."""


def _did_you_mean(name: str, known: Iterable[str]) -> str | None:
    """A hint naming the known names ``name`` may be a slip for: differing
    only in case, or close in spelling; None when none is."""
    names = sorted(set(known) - {name})
    same = [n for n in names if n.lower() == name.lower()]
    if same:
        return f"symbols are case-sensitive: did you mean {' or '.join(same)}?"
    close = difflib.get_close_matches(name, names, n=2, cutoff=0.75)
    if close:
        return f"did you mean {' or '.join(close)}?"
    return None
