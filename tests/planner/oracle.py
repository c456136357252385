"""An independent enumerator: the thesis's depth-first planner (4.5), literally.

Written from the thesis, not from the planner, for the differential property
tests: every derivation of the goal, in depth-first order (method versions in
domain order, bindings in state order), each with its cost, then stably
sorted by cost, as the planner claims to return them. Channels are checked,
merged and costed once the stack is empty. Beyond the thesis, as the planner:
``(any A B)`` channels (local on one robot, global between two), devices
weighted as devices, costs ranked at the levels the planner ranks them
(:mod:`cfgplan.planner.costs`), and with a ``reliability`` weight W, W·(−ln p)
for each functionality's reliability p and for each global channel between two
robots, p the most reliable medium between them (7.2).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from cfgplan.configuration.cost import Weights
from cfgplan.configuration.matching import satisfying
from cfgplan.configuration.media import Demand, assign
from cfgplan.ir.model import Atom, Functionality, Method, Negation
from cfgplan.notation import atom_text
from cfgplan.planner.costs import Levels, unit_of
from cfgplan.problem import Problem

Ground = tuple[str, ...]
Env = dict[str, str]
Identity = tuple[frozenset[Ground], frozenset[tuple[object, ...]], frozenset[str]]


@dataclass(frozen=True)
class _Wire:
    """A channel between two labels, as the depth-first planner keeps it."""

    kind: str
    robots: Ground
    source: int
    target: int
    data: Ground
    bandwidth: float | None


@dataclass(frozen=True)
class _Node:
    stack: tuple[tuple[int, Ground, frozenset[Ground]], ...]  # (label, call, ancestors)
    placed: tuple[tuple[int, Ground, Functionality, Env], ...]  # (label, key, schema, binding)
    channels: tuple[_Wire, ...]
    effects: tuple[str, ...]
    next_label: int


def _subst(atom: Atom, env: dict[str, str]) -> Ground:
    return (atom.predicate, *(env.get(t, t) for t in atom.args))


def _effects(effects: Sequence[Atom | Negation], env: dict[str, str]) -> tuple[str, ...]:
    return tuple(
        f"(not {atom_text(_subst(e.atom, env))})"
        if isinstance(e, Negation)
        else atom_text(_subst(e, env))
        for e in effects
    )


def _head(name: Atom, call: Ground) -> dict[str, str] | None:
    """The binding of a name to a call; None when a constant or a repeated
    variable of the name disagrees with the call."""
    env: dict[str, str] = {}
    for term, value in zip(name.args, call[1:], strict=True):
        if not term.startswith("?"):
            if term != value:
                return None
        elif env.setdefault(term, value) != value:
            return None
    return env


def _ports(env: Env, side: Sequence[Atom]) -> set[Ground]:
    """A placed functionality's inputs or outputs under the binding it was
    placed with: its preconditions may bind variables its ports use."""
    return {_subst(a, env) for a in side}


def depth_first(problem: Problem, weights: Weights) -> list[tuple[float, Identity]]:
    """Every derivation of the goal, in the depth-first order of thesis 4.5
    (method versions in domain order, bindings in state order), each with its
    cost; then stably sorted by cost, as the planner claims to return them.

    Written from the thesis, not from the planner: channels are checked,
    merged and costed once the stack is empty.
    """
    domain, state = problem.domain, problem.state
    facts = list(dict.fromkeys((a.predicate, *a.args) for a in state.facts))  # a set (4.4)
    found: list[tuple[float, Identity]] = []
    devices = {f[1] for f in facts if f[0] == "device" and len(f) == 2}
    values = [weights.robot, weights.device, weights.global_, weights.local, weights.functionality]
    values += [f.cost for f in domain.functionalities if f.cost is not None]
    # Costs ranked as the planner ranks them: logarithms have no unit.
    levels = Levels(None if weights.reliability else unit_of(values))
    links: dict[tuple[str, str], float] = {}  # the most reliable medium of each link
    for m in state.media:
        p = 1.0 if m.reliability is None else m.reliability
        links[m.sender, m.receiver] = max(p, links.get((m.sender, m.receiver), 0.0))

    def unreliable(p: float) -> float:
        return weights.reliability * -math.log(p) if weights.reliability else 0.0

    def finish(node: _Node) -> None:
        where = {label: key for label, key, _, _ in node.placed}
        schema = {label: f for label, _, f, _ in node.placed}
        binding = {label: env for label, _, _, env in node.placed}
        merged: dict[tuple[str, int, int, Ground], _Wire] = {}
        for ch in node.channels:
            if ch.source not in where or ch.target not in where:
                return
            sender, receiver = where[ch.source][1], where[ch.target][1]
            wanted = (ch.robots[0], ch.robots[0]) if ch.kind == "local" else ch.robots
            if (sender, receiver) != wanted:
                return
            ident = (ch.kind, ch.source, ch.target, ch.data)
            kept = merged.setdefault(ident, ch)  # identical channels merge (4.5) ...
            if ch.bandwidth is not None and (
                kept.bandwidth is None or ch.bandwidth > kept.bandwidth
            ):
                merged[ident] = replace(kept, bandwidth=ch.bandwidth)  # ... keeping the most
        channels = list(merged.values())
        fed = {(ch.target, ch.data) for ch in channels}
        for ch in channels:
            if ch.data not in _ports(binding[ch.source], schema[ch.source].outputs):
                return
        for label, _, f, env in node.placed:
            if any((label, need) not in fed for need in _ports(env, f.inputs)):
                return
        unsorted = set(where)
        while True:  # the sort of 5.1: take functionalities with no unsorted input
            ready = {
                n
                for n in unsorted
                if not any(c.target == n and c.source in unsorted for c in channels)
            }
            if not ready:
                break
            unsorted -= ready
        if unsorted:  # a cycle
            return
        if state.media:
            demands = [
                Demand(where[c.source][1], where[c.target][1], c.bandwidth or 0.0)
                if c.kind == "global" and where[c.source][1] != where[c.target][1]
                else None
                for c in channels
            ]
            if not assign(demands, state.media).ok:
                return
        agents = {key[1] for key in where.values()}
        cost = sum(weights.device if a in devices else weights.robot for a in agents)
        cost += sum(weights.global_ if c.kind == "global" else weights.local for c in channels)
        cost += sum(
            (f.cost if f.cost is not None else weights.functionality)
            + unreliable(1.0 if f.reliability is None else f.reliability)
            for _, _, f, _ in node.placed
        )
        cost += sum(
            unreliable(links.get((where[c.source][1], where[c.target][1]), 1.0))
            for c in channels
            if c.kind == "global" and where[c.source][1] != where[c.target][1]
        )
        identity: Identity = (
            frozenset(where.values()),
            frozenset(
                (c.kind, where[c.source], where[c.target], c.data, c.bandwidth) for c in channels
            ),
            frozenset(node.effects),
        )
        found.append((levels.cost(cost), identity))

    def visit(node: _Node) -> None:
        if not node.stack:
            finish(node)
            return
        (label, call, ancestors), rest = node.stack[0], node.stack[1:]
        sig = (call[0], len(call) - 1)
        versions = domain.method_versions(sig)
        if not versions:
            f = domain.functionality(sig)
            if f is None:
                return
            existing = next((lab for lab, key, _, _ in node.placed if key == call), None)
            if existing is not None:  # "check if it already exists in C" (4.5, 2a)
                moved = tuple(
                    _Wire(
                        c.kind,
                        c.robots,
                        existing if c.source == label else c.source,
                        existing if c.target == label else c.target,
                        c.data,
                        c.bandwidth,
                    )
                    for c in node.channels
                )
                visit(_Node(rest, node.placed, moved, node.effects, node.next_label))
                return
            head = _head(f.name, call)
            for env in satisfying(f.precond, facts, head) if head is not None else ():
                visit(
                    _Node(
                        rest,
                        (*node.placed, (label, call, f, env)),
                        node.channels,
                        node.effects + _effects(f.postcond, env),
                        node.next_label,
                    )
                )
            return
        if call in ancestors:
            return
        for m in versions:
            head = _head(m.name, call)
            for env in satisfying(m.precond, facts, head) if head is not None else ():
                child = expand(node, label, call, ancestors, rest, m, env)
                if child is not None:
                    visit(child)

    def expand(
        node: _Node,
        label: int,
        call: Ground,
        ancestors: frozenset[Ground],
        rest: tuple[tuple[int, Ground, frozenset[Ground]], ...],
        m: Method,
        env: dict[str, str],
    ) -> _Node | None:
        fresh = {item.label: node.next_label + i for i, item in enumerate(m.body)}
        block: list[_Wire] = []
        for spec in m.channels:
            robots = tuple(env.get(t, t) for t in spec.robots)
            data = _subst(spec.data, env)
            if any(t.startswith("?") for t in (*robots, *data[1:])):
                return None
            kind = spec.kind
            if kind == "any":  # local on one robot, global between two
                one = robots[0] == robots[1]
                kind, robots = ("local", robots[:1]) if one else ("global", robots)
            block.append(
                _Wire(kind, robots, fresh[spec.source], fresh[spec.target], data, spec.bandwidth)
            )
        wires: list[_Wire] = []
        for c in node.channels:
            source, bandwidth = c.source, c.bandwidth
            if c.source == label:  # 4.5, 3d: re-wire the sending end through :out
                port = next((p for p in m.outputs if _subst(p.data, env) == c.data), None)
                if port is None:
                    return None
                source = fresh[port.label]
                if bandwidth is None and c.kind == "global":
                    bandwidth = port.bandwidth
            targets = [c.target]
            if c.target == label:  # ... and the receiving end through :in (both if both)
                targets = [fresh[p.label] for p in m.inputs if _subst(p.data, env) == c.data]
                if not targets:
                    return None
            wires += [_Wire(c.kind, c.robots, source, t, c.data, bandwidth) for t in targets]
        body = []
        for item in m.body:
            ground = _subst(item.call, env)
            if any(t.startswith("?") for t in ground[1:]):
                return None
            body.append((fresh[item.label], ground, ancestors | {call}))
        return _Node(
            (*body, *rest),
            node.placed,
            (*block, *wires),
            node.effects + _effects(m.postcond, env),
            node.next_label + len(m.body),
        )

    goal = problem.goal_call
    visit(_Node(((1, goal, frozenset()),), (), (), (), 2))
    found.sort(key=lambda pair: pair[0])  # stable: depth-first order among equal costs
    return found
