"""Which channel feeds which input of a call, which output goes where (5.3, step 4).

For each functionality of an individual configuration, step 4(b) of 5.3 looks
for the channels whose target is the functionality and puts each "at the
position specified by the data type": here the position of the matching
``:in`` descriptor of the functionality operator, instantiated with the
instance's arguments. Step 4(c) does the same for outputs and ``:out``.

Decisions where the thesis is silent:

* several channels feeding one input (possible once functionalities are
  reused) are all kept, in channel order; the backends pass them as a list;
* an input no channel feeds keeps an empty list (a configuration the planner
  returns is information admissible, so this does not happen there);
* when two inputs have the same descriptor, the channels fill them in order,
  one each, the last input taking any extra ones.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from cfgplan.backends.divide import Individual, divide
from cfgplan.backends.sort import sort_functionalities
from cfgplan.configuration.describe import channel_text
from cfgplan.configuration.model import Configuration, FunctionalityInstance
from cfgplan.diagnostics import CfgplanError, error
from cfgplan.ir.model import Atom, Domain
from cfgplan.notation import call_text
from cfgplan.safe_names import file_stems, safe_stem

__all__ = ["RESERVED_STEMS", "Call", "Data", "RobotPart", "deploy", "wire"]

Data = tuple[str, ...]
"""An instantiated data descriptor, e.g. ``("pos", "Emil", "Door1")``."""


@dataclass(frozen=True)
class Call:
    """One functionality call of an individual configuration.

    ``inputs[i]`` lists the channels (0-based indexes into the robot's channel
    list) feeding the i-th ``:in`` descriptor, ``outputs[j]`` those the j-th
    ``:out`` descriptor is written to. ``freq`` is the operator's ``:freq``
    (3.2), if it has one.
    """

    functionality: FunctionalityInstance
    input_data: tuple[Data, ...]
    output_data: tuple[Data, ...]
    inputs: tuple[tuple[int, ...], ...]
    outputs: tuple[tuple[int, ...], ...]
    freq: float | None = None

    @property
    def objects(self) -> tuple[str, ...]:
        """The arguments after the robot: what the call passes quoted (5.2.1)."""
        return self.functionality.args[1:]


def descriptors(domain: Domain, f: FunctionalityInstance) -> tuple[tuple[Data, ...], ...]:
    """The ``:in`` and ``:out`` descriptors of ``f``'s operator, instantiated."""
    operator = domain.functionality((f.name, len(f.args)))
    if operator is None:
        raise error(
            f"{f}: the domain has no functionality operator {f.name} with {len(f.args)} argument(s)"
        )
    binding = dict(zip(operator.name.args, f.args, strict=True))

    def instantiate(atom: Atom) -> Data:
        return (atom.predicate, *(binding.get(a, a) for a in atom.args))

    return (
        tuple(instantiate(a) for a in operator.inputs),
        tuple(instantiate(a) for a in operator.outputs),
    )


def wire(individual: Individual, domain: Domain) -> tuple[Call, ...]:
    """The calls of ``individual`` in its (sorted) order, with their channels."""
    return tuple(_call(individual, domain, f) for f in individual.functionalities)


def _call(individual: Individual, domain: Domain, f: FunctionalityInstance) -> Call:
    input_data, output_data = descriptors(domain, f)
    inputs: list[list[int]] = [[] for _ in input_data]
    outputs: list[list[int]] = [[] for _ in output_data]
    for i, ch in enumerate(individual.channels):
        if ch.target == f.label:
            _place(inputs, input_data, i, ch.data, f, "input", channel_text(ch))
        if ch.source == f.label:
            outputs[_position(output_data, ch.data, f, "output", channel_text(ch))].append(i)
    operator = domain.functionality((f.name, len(f.args)))
    return Call(
        f,
        input_data,
        output_data,
        tuple(tuple(x) for x in inputs),
        tuple(tuple(x) for x in outputs),
        None if operator is None else operator.freq,
    )


def _place(
    slots: list[list[int]],
    data: Sequence[Data],
    channel: int,
    carried: Data,
    f: FunctionalityInstance,
    what: str,
    shown: str,
) -> None:
    """Put an input channel on the first empty input with its descriptor."""
    positions = [k for k, d in enumerate(data) if d == carried]
    if not positions:
        raise _mismatch(data, carried, f, what, shown)
    free = [k for k in positions if not slots[k]]
    slots[free[0] if free else positions[-1]].append(channel)


def _position(
    data: Sequence[Data], carried: Data, f: FunctionalityInstance, what: str, shown: str
) -> int:
    for k, d in enumerate(data):
        if d == carried:
            return k
    raise _mismatch(data, carried, f, what, shown)


def _mismatch(
    data: Sequence[Data], carried: Data, f: FunctionalityInstance, what: str, shown: str
) -> CfgplanError:
    have = ", ".join(call_text(d) for d in data) or "none"
    return error(
        f"{shown} carries {call_text(carried)}, but {f} has no such {what} (its {what}s: {have})"
    )


RESERVED_STEMS = ("configuration", "run_all")
"""Stems of the files an emission writes besides the robots' ones."""


@dataclass(frozen=True)
class RobotPart:
    """An individual configuration with its calls wired: what a backend emits.

    ``file_stem`` is the safe name of the robot's file (:mod:`cfgplan.safe_names`),
    set by :func:`deploy` so that the robots of one configuration never share one.
    """

    individual: Individual
    calls: tuple[Call, ...]
    file_stem: str | None = None

    @property
    def robot(self) -> str:
        return self.individual.robot

    @property
    def stem(self) -> str:
        """The robot's file name without suffix: ``emil`` for Emil."""
        return self.file_stem or safe_stem(self.robot)


def deploy(config: Configuration, domain: Domain) -> tuple[RobotPart, ...]:
    """Sort, divide and wire ``config`` (5.1, 5.3): one part per robot, each
    with a file stem of its own."""
    order = sort_functionalities(config)
    individuals = divide(config, order)
    stems = file_stems((ind.robot for ind in individuals), RESERVED_STEMS)
    return tuple(RobotPart(ind, wire(ind, domain), stems[ind.robot]) for ind in individuals)
