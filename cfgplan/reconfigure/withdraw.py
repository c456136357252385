"""Which facts a failure takes out of the world state, read off the domain (5.5, 6.2.2 step 3).

In 6.2.2 step 3 Emil's compass gives wrong data and the thesis's operator
removes the compasses from the state by hand; in 6.3.2 the laser fails and
``laser(Emil)`` goes. Here the facts a failure withdraws follow from the
domain, never from a table:

* **A failed sensing resource** ``f = name(R, a...)`` (3.3: a functionality
  without inputs, a sensor) withdraws the facts that justify placing it:

  1. its *justification*: the precondition atoms of ``name``'s own operator,
     and those that *every* method version calling ``name`` in its body
     tests, each instantiated by the binding the call gives (an atom with a
     variable the call does not bind depends on more than ``f``);
  2. of those, the ones that mention ``R``: a failure on a robot says
     something about that robot only;
  3. and whose predicate is *specific* to ``name``: every method version
     that tests the predicate *reaches* ``name`` (calls it, or calls a method
     one of whose versions reaches it); the preconditions of other
     functionality operators do not count (``measure-robot-orient-compass``
     tests the compasses it reads from).

  Only facts the state holds are withdrawn. A failed ``compass(Emil)``
  withdraws ``(compass Emil)`` (the thesis's operator removes both compasses;
  with one gone the compass version of ``get-robot-orient`` no longer
  applies, which gives the same configuration, 47); ``laser(Emil)``
  withdraws ``(laser Emil)`` but not ``(robot Emil)``, which the sonar
  version of ``get-global-pos`` tests without ever using a laser (rule 3);
  ``odometer(Pippi)`` withdraws ``(odometer Pippi)`` but not ``(sonar
  Pippi)``, which the laser version of ``get-global-pos``, also calling the
  odometer, does not test (rule 1).

  Any other failed instance withdraws nothing: a computation (inputs and
  outputs) says nothing about the world, and an action resource (no outputs)
  is what the goal asks of its robot — its justification is the top
  method's, such as ``(robot Vacu)`` for ``dock(Vacu, Charger1)``, which the
  failure does not make false. Every failed instance, whatever its kind, is
  kept out of later configurations
  (:class:`~cfgplan.reconfigure.situation.Situation`).

* **A lost robot** (its process ended, its liveliness went): everything on it
  is gone, so every fact that names it is withdrawn (and nothing may be
  placed on it).

* **A failed medium** (4.6) is taken out of the state's media.
"""

from __future__ import annotations

from collections.abc import Iterator

from cfgplan.planner.task import FunctionalitySchema, Ground, MethodSchema, Task, Test, TestKind
from cfgplan.planner.unify import Bindings, bind_name, is_ground, substitute, unify

__all__ = [
    "is_sensing",
    "justification",
    "reaching",
    "specific",
    "withdrawn_by_failure",
    "withdrawn_by_loss",
]

Signature = tuple[str, int]


def is_sensing(schema: FunctionalitySchema) -> bool:
    """A sensing resource (3.3): no inputs."""
    return not schema.inputs


def _calls(method: MethodSchema) -> Iterator[tuple[str, ...]]:
    for _, call in method.body:
        yield call


def _signature(call: tuple[str, ...]) -> Signature:
    return (call[0], len(call) - 1)


def reaching(task: Task, target: Signature) -> frozenset[tuple[Signature, int]]:
    """The method versions (signature, version) that reach ``target``: call
    it in their body, or call a method one of whose versions reaches it."""
    reached: set[Signature] = {target}
    versions: set[tuple[Signature, int]] = set()
    changed = True
    while changed:
        changed = False
        for signature, methods in task.methods.items():
            for method in methods:
                mark = (signature, method.version)
                if mark not in versions and any(_signature(c) in reached for c in _calls(method)):
                    versions.add(mark)
                    if signature not in reached:
                        reached.add(signature)
                    changed = True
    return frozenset(versions)


def specific(task: Task, target: Signature) -> frozenset[Signature]:
    """Precondition predicates that only method versions reaching ``target``
    (and ``target``'s own operator) test; other operators do not count."""
    reach = reaching(task, target)
    operator = task.functionalities.get(target)
    inside: set[Signature] = set()
    if operator is not None:
        inside.update(_signature(t.pattern) for t in operator.tests if t.kind is TestKind.ATOM)
    outside: set[Signature] = set()
    for signature, methods in task.methods.items():
        for method in methods:
            side = inside if (signature, method.version) in reach else outside
            side.update(_signature(t.pattern) for t in method.tests if t.kind is TestKind.ATOM)
    return frozenset(inside - outside)


def _ground_atoms(tests: tuple[Test, ...], env: Bindings) -> set[Ground]:
    out: set[Ground] = set()
    for test in tests:
        if test.kind is TestKind.ATOM:
            atom = substitute(test.pattern, env)
            if is_ground(atom):
                out.add(atom)
    return out


def justification(task: Task, schema: FunctionalitySchema, call: Ground) -> set[Ground]:
    """Rule 1: the operator's own ground preconditions, and those every call
    site of ``schema`` in a method body has."""
    own = bind_name(schema.params, call[1:])
    found = set() if own is None else _ground_atoms(schema.tests, own)
    shared: set[Ground] | None = None
    target = (schema.name, len(schema.params))
    for methods in task.methods.values():
        for method in methods:
            for site in _calls(method):
                if _signature(site) != target:
                    continue
                env = unify(site, call, {})
                if env is None:
                    continue
                atoms = _ground_atoms(method.tests, env)
                shared = atoms if shared is None else shared & atoms
    return found | (shared or set())


def withdrawn_by_failure(task: Task, instance: Ground) -> tuple[Ground, ...]:
    """The facts of ``task``'s state that the failure of ``instance``
    (``("compass", "Emil")``) withdraws, in state order (module docstring)."""
    schema = task.functionality(instance)
    if schema is None or not is_sensing(schema) or len(instance) < 2:
        return ()
    robot = instance[1]
    allowed = specific(task, (schema.name, len(schema.params)))
    chosen = {
        atom
        for atom in justification(task, schema, instance)
        if robot in atom[1:] and _signature(atom) in allowed
    }
    return tuple(f for f in task.facts if f in chosen)


def withdrawn_by_loss(task: Task, robot: str) -> tuple[Ground, ...]:
    """Every fact of the state that names ``robot``, in state order."""
    return tuple(f for f in task.facts if robot in f[1:])
