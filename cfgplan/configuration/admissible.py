"""An independent admissibility checker for configurations (thesis 3.5, 4.6).

A configuration ``<F, Ch>`` is admissible in a world state when every input of
every functionality is fed by a channel from a functionality that produces it
(information), the preconditions of every functionality hold in the state
(causal), and the media can carry the global channels (communication, 3.5 and
4.6). Its cost is ``10·robots + 3·global + local + functionalities`` (3.5),
an agent the state declares ``(device X)`` weighted as a device.

The planner claims all of this for what it returns ("information and causal
admissibility are guaranteed implicitly by the planning algorithm", 4.6). This
module re-checks it from the domain, the state and the configuration alone and
shares no code with :mod:`cfgplan.planner`: it has its own precondition matcher
(:mod:`cfgplan.configuration.matching`) and its own reading of labels,
locations, channels, media and cost. Only the ``(eval ...)`` interpreter of
:mod:`cfgplan.check.evaluate` is shared.

:func:`problems` returns the reasons a configuration is not admissible, one
line each and prefixed by the condition it violates; an empty list means
admissible.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from cfgplan.configuration.cost import Weights, fmt
from cfgplan.configuration.matching import Env, Ground, atom_of, is_var, satisfying, subst, unify
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.ir.model import Domain, Functionality, Medium, State
from cfgplan.notation import atom_text


def _channel_text(index: int, ch: Channel) -> str:
    return f"channel {index} ({ch.kind} {ch.source} -> {ch.target} {atom_text(ch.data)})"


# -- the checks ---------------------------------------------------------------


class _Checker:
    def __init__(
        self,
        config: Configuration,
        domain: Domain,
        state: State,
        weights: Weights | None,
        reliability: Mapping[Ground, float],
    ) -> None:
        self.config = config
        self.domain = domain
        self.state = state
        self.weights = weights
        self.reliability = reliability
        self.found: list[str] = []
        self.facts = [atom_of(a) for a in state.facts]
        # label -> instance (first one when a label repeats)
        self.by_label: dict[str, FunctionalityInstance] = {}
        # label -> (schema, binding of its name) for instances that resolve
        self.schemas: dict[str, tuple[Functionality, Env]] = {}

    def report(self, condition: str, message: str) -> None:
        self.found.append(f"{condition}: {message}")

    def run(self) -> list[str]:
        self.labels()
        self.functionalities()
        self.channels()
        self.information()
        self.duplicates()
        self.cycles()
        self.communication()
        self.cost()
        return self.found

    # labels and functionalities ---------------------------------------------

    def labels(self) -> None:
        for f in self.config.functionalities:
            if f.label in self.by_label:
                self.report(
                    "labels",
                    f"label {f.label} names both {self.by_label[f.label]} and {f}",
                )
            else:
                self.by_label[f.label] = f

    def functionalities(self) -> None:
        for label, f in self.by_label.items():
            schema = self.domain.functionality((f.name, len(f.args)))
            if schema is None:
                self.report(
                    "domain",
                    f"{f} names no functionality ({f.name} ...) with "
                    f"{len(f.args)} argument(s) of the domain",
                )
                continue
            if not f.args:
                self.report("location", f"{f} has no first argument to run on")
            variables = [a for a in f.args if is_var(a)]
            if variables:
                self.report("causal", f"{f} is not ground: {', '.join(variables)}")
            env = unify(atom_of(schema.name), (f.name, *f.args), {})
            if env is None:
                self.report("domain", f"{f} does not match the schema {schema.name}")
                continue
            options = list(satisfying(schema.precond, self.facts, env))
            if not options:
                conditions = " ".join(str(c) for c in schema.precond)
                self.report(
                    "causal",
                    f"the preconditions of {f} do not hold in the state: {conditions}",
                )
            self.schemas[label] = (schema, self._fitting(label, schema, options) or env)

    def _fitting(self, label: str, schema: Functionality, options: list[Env]) -> Env | None:
        """The first binding of the preconditions under which the instance's
        ports match its channels: its preconditions may bind variables its
        inputs and outputs use (``(loc ?r)`` with ``(in ?r ?room)`` produces
        ``(pos ?r ?room)``), and the configuration does not record the binding.
        None when no binding fits (the checks below then report it)."""
        sent = {ch.data for ch in self.config.channels if ch.source == label}
        received = {ch.data for ch in self.config.channels if ch.target == label}
        for env in options:
            outputs = {subst(atom_of(a), env) for a in schema.outputs}
            inputs = {subst(atom_of(a), env) for a in schema.inputs}
            if sent <= outputs and inputs == received:
                return env
        return options[0] if options else None

    def _ports(self, label: str, side: str) -> list[Ground] | None:
        """The instantiated inputs or outputs of a resolved instance, else None."""
        if label not in self.schemas:
            return None
        schema, env = self.schemas[label]
        atoms = schema.inputs if side == "in" else schema.outputs
        return [subst(atom_of(a), env) for a in atoms]

    # channels -----------------------------------------------------------------

    def channels(self) -> None:
        for i, ch in enumerate(self.config.channels):
            shown = _channel_text(i, ch)
            src, dst = self.by_label.get(ch.source), self.by_label.get(ch.target)
            for end, role, inst in ((ch.source, "source", src), (ch.target, "target", dst)):
                if inst is None:
                    self.report("channel", f"{shown}: its {role} {end} is no functionality")
            for inst, recorded, role in (
                (src, ch.source_robot, "source"),
                (dst, ch.target_robot, "target"),
            ):
                if inst is not None and inst.args and inst.args[0] != recorded:
                    self.report(
                        "location",
                        f"{shown}: {role}_robot is {recorded} but {inst} runs on {inst.args[0]}",
                    )
            if ch.kind == "local":
                where = {self._robot(ch.source, ch.source_robot)}
                where.add(self._robot(ch.target, ch.target_robot))
                if len(where) > 1:
                    self.report(
                        "location",
                        f"{shown}: a local channel joins two robots, {' and '.join(sorted(where))}",
                    )
            produced = self._ports(ch.source, "out")
            if produced is not None and ch.data not in produced:
                assert src is not None
                self.report("information", f"{shown}: {src} does not produce it")
            consumed = self._ports(ch.target, "in")
            if consumed is not None and ch.data not in consumed:
                assert dst is not None
                self.report("information", f"{shown}: {dst} does not consume it")

    def _robot(self, label: str, recorded: str) -> str:
        """Where the functionality ``label`` runs (the recorded robot if unknown)."""
        inst = self.by_label.get(label)
        return inst.args[0] if inst is not None and inst.args else recorded

    def information(self) -> None:
        fed = {(ch.target, ch.data) for ch in self.config.channels}
        for label, inst in self.by_label.items():
            for need in self._ports(label, "in") or []:
                if (label, need) not in fed:
                    self.report(
                        "information", f"input {atom_text(need)} of {inst} is fed by no channel"
                    )

    def duplicates(self) -> None:
        seen: dict[tuple[str, str, str, Ground], int] = {}
        for i, ch in enumerate(self.config.channels):
            key = (ch.kind, ch.source, ch.target, ch.data)
            if key in seen:
                self.report(
                    "duplicate",
                    f"{_channel_text(i, ch)} repeats channel {seen[key]}",
                )
            else:
                seen[key] = i

    def cycles(self) -> None:
        succ: dict[str, set[str]] = {label: set() for label in self.by_label}
        for ch in self.config.channels:
            if ch.source in succ and ch.target in succ:
                succ[ch.source].add(ch.target)
        indegree = dict.fromkeys(succ, 0)
        for targets in succ.values():
            for t in targets:
                indegree[t] += 1
        ready = [n for n, d in indegree.items() if d == 0]
        while ready:
            n = ready.pop()
            for m in succ[n]:
                indegree[m] -= 1
                if indegree[m] == 0:
                    ready.append(m)
        stuck = [n for n, d in indegree.items() if d > 0]
        if stuck:
            self.report("cycle", "the channels form a cycle through " + ", ".join(sorted(stuck)))

    # communication ------------------------------------------------------------

    def communication(self) -> None:
        media = self.state.media
        assignments = self.config.media
        if not media:
            if assignments:
                self.report(
                    "communication",
                    f"{len(assignments)} channel(s) are assigned to media, "
                    "but the state declares none",
                )
            return
        chosen: dict[int, int] = {}
        for a in assignments:
            if not 0 <= a.channel < len(self.config.channels):
                self.report("communication", f"an assignment names no channel {a.channel}")
                continue
            if not 0 <= a.medium < len(media):
                self.report("communication", f"channel {a.channel} is assigned to no medium")
                continue
            if a.channel in chosen:
                self.report(
                    "communication", f"channel {a.channel} is assigned to more than one medium"
                )
                continue
            chosen[a.channel] = a.medium
        loads = [0.0] * len(media)
        for i, ch in enumerate(self.config.channels):
            shown = _channel_text(i, ch)
            sender = self._robot(ch.source, ch.source_robot)
            receiver = self._robot(ch.target, ch.target_robot)
            needs = ch.kind == "global" and sender != receiver
            if i not in chosen:
                if needs:
                    self.report(
                        "communication",
                        f"{shown} goes from {sender} to {receiver} but no medium carries it",
                    )
                continue
            m = media[chosen[i]]
            if not needs:
                self.report(
                    "communication",
                    f"{shown} is assigned to medium {chosen[i]} ({_medium(m)}) "
                    "but needs none: it does not join two robots",
                )
                continue
            if (m.sender, m.receiver) != (sender, receiver):
                self.report(
                    "communication",
                    f"{shown} goes from {sender} to {receiver} but is assigned to "
                    f"medium {chosen[i]} ({_medium(m)})",
                )
            loads[chosen[i]] += ch.bandwidth or 0.0
        for j, m in enumerate(media):
            if loads[j] > m.capacity:
                self.report(
                    "communication",
                    f"medium {j} ({_medium(m)}) carries {fmt(loads[j])}, "
                    f"more than its capacity {fmt(m.capacity)}",
                )

    # cost ---------------------------------------------------------------------

    def _reliability(self) -> float:
        """The product of the functionalities' reliabilities and, for each
        global channel between two robots, of the most reliable medium between
        them (7.2; 1 where nothing is said)."""
        product = 1.0
        for f in self.config.functionalities:
            schema = self.domain.functionality((f.name, len(f.args)))
            p = self.reliability.get((f.name, *f.args))
            if p is None:
                p = schema.reliability if schema is not None and schema.reliability else 1.0
            product *= p
        best: dict[tuple[str, str], float] = {}
        for m in self.state.media:
            p = m.reliability if m.reliability is not None else 1.0
            best[(m.sender, m.receiver)] = max(p, best.get((m.sender, m.receiver), 0.0))
        for ch in self.config.channels:
            sender = self._robot(ch.source, ch.source_robot)
            receiver = self._robot(ch.target, ch.target_robot)
            if ch.kind == "global" and sender != receiver:
                product *= best.get((sender, receiver), 1.0)
        return product

    def cost(self) -> None:
        w = self.weights if self.weights is not None else self.config.weights
        if self.weights is not None and self.config.weights != self.weights:
            self.report("cost", f"the configuration records weights {self.config.weights}, not {w}")
        agents = {f.args[0] for f in self.config.functionalities if f.args}
        devices = {fact[1] for fact in self.facts if fact[0] == "device" and len(fact) == 2}
        robots = agents - devices
        total = w.robot * len(robots) + w.device * len(agents & devices)
        if set(self.config.devices) != agents & devices:
            self.report(
                "cost",
                f"the configuration lists devices {sorted(self.config.devices)}, but the state "
                f"declares {sorted(agents & devices)} of its agents devices",
            )
        for ch in self.config.channels:
            total += w.global_ if ch.kind == "global" else w.local
        for f in self.config.functionalities:
            schema = self.domain.functionality((f.name, len(f.args)))
            own = schema.cost if schema is not None else None
            total += own if own is not None else w.functionality
        product = self._reliability()
        if not math.isclose(product, self.config.reliability, rel_tol=1e-9):
            self.report(
                "cost",
                f"the configuration says reliability {self.config.reliability:g}, "
                f"but its parts give {product:g}",
            )
        if w.reliability:
            total += w.reliability * -math.log(product)
        if not math.isclose(total, self.config.cost, rel_tol=1e-9, abs_tol=1e-9):
            self.report(
                "cost",
                f"the configuration says {fmt(self.config.cost)}, but its parts cost "
                f"{fmt(total)} ({len(robots)} robots, "
                + (f"{len(agents & devices)} devices, " if agents & devices else "")
                + f"{self.config.global_channels} global "
                f"and {self.config.local_channels} local channels, "
                f"{len(self.config.functionalities)} functionalities; weights {w})",
            )


def _medium(m: Medium) -> str:
    return f"{m.type} {m.sender}->{m.receiver}, capacity {fmt(m.capacity)}"


def problems(
    config: Configuration,
    domain: Domain,
    state: State,
    weights: Weights | None = None,
    reliability: Mapping[Ground, float] | None = None,
) -> list[str]:
    """Why ``config`` is not admissible in ``state`` under ``domain`` (thesis 3.5);
    empty when it is.

    Each reason starts with the condition it violates: ``labels``, ``domain``,
    ``causal``, ``channel``, ``location``, ``information``, ``duplicate``,
    ``cycle``, ``communication`` or ``cost``. The cost is recomputed with
    ``weights`` when given (and the configuration must record the same
    weights), else with the configuration's own weights; ``reliability``
    replaces the reliability of some functionality instances, as the planner's
    task may (:func:`cfgplan.planner.task.compile_task`).
    """
    return _Checker(config, domain, state, weights, reliability or {}).run()
