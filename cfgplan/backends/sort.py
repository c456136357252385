"""Sorting a configuration by its information flow: the FIFO algorithm of 5.1.

Input is the unsorted functionality list uC (the planner's list order, newest
first), output the sorted list sC; a FIFO ``c`` collects the channels whose
data will be available. Step 1 takes a functionality whose input channels are
all in ``c`` (one without input trivially qualifies), appends its output
channels to ``c`` and moves it to the end of sC. Step 2 reports a cycle when
no functionality qualifies while uC is not empty.

The thesis does not say where step 1 starts looking. Scanning uC cyclically,
continuing after the last pick, reproduces its order of 5.4 (F117, F116,
F114, F129, F118, F115, F113, F109 from F109, F113, F129, F118, F117, F116,
F115, F114), so that is the rule here.
"""

from __future__ import annotations

from cfgplan.configuration.model import Configuration, FunctionalityInstance
from cfgplan.diagnostics import error

__all__ = ["sort_functionalities"]


def sort_functionalities(config: Configuration) -> tuple[FunctionalityInstance, ...]:
    """The functionalities of ``config`` in execution order (5.1).

    Raises CfgplanError when a channel comes from a functionality that is not
    in the configuration, or when the configuration contains a cycle (naming
    the functionalities on it).
    """
    labels = {f.label for f in config.functionalities}
    inputs: dict[str, set[int]] = {f.label: set() for f in config.functionalities}
    outputs: dict[str, list[int]] = {f.label: [] for f in config.functionalities}
    for i, ch in enumerate(config.channels):
        for end in (ch.source, ch.target):
            if end not in labels:
                raise error(
                    f"channel {i + 1} ({ch.source} -> {ch.target}) names {end}, "
                    "which is not a functionality of the configuration"
                )
        inputs[ch.target].add(i)
        outputs[ch.source].append(i)

    unsorted = list(config.functionalities)  # uC
    result: list[FunctionalityInstance] = []  # sC
    available: set[int] = set()  # c; step 1 only asks what is in it, not in which order
    at = 0  # where the cyclic scan of step 1 goes on
    while unsorted:
        n = len(unsorted)
        pick = next(
            (
                (at + step) % n
                for step in range(n)
                if inputs[unsorted[(at + step) % n].label] <= available
            ),
            None,
        )
        if pick is None:  # step 2
            raise _cycle_error(config, unsorted, inputs, available)
        f = unsorted.pop(pick)
        available.update(outputs[f.label])
        result.append(f)
        at = pick  # the functionality after f now stands where f stood
    return tuple(result)


def _cycle_error(
    config: Configuration,
    unsorted: list[FunctionalityInstance],
    inputs: dict[str, set[int]],
    available: set[int],
) -> Exception:
    """Step 2: walk back along missing inputs from the first stuck functionality
    until a functionality repeats; the repeated stretch is a cycle."""
    by_label = {f.label: f for f in unsorted}
    path: list[str] = []
    label = unsorted[0].label
    while label not in path:
        path.append(label)
        missing = min(inputs[label] - available)
        label = config.channels[missing].source
        # every channel that is not available comes from an unsorted functionality
        assert label in by_label
    cycle = path[path.index(label) :]
    cycle.reverse()  # in the direction the data flows
    cycle.append(cycle[0])
    text = " -> ".join(str(by_label[x]) for x in cycle)
    return error(
        f"the configuration contains a cycle and cannot be sorted (5.1): {text}",
        hint="a method whose channels feed a functionality's output back to its "
        "input makes such configurations; every functionality on the cycle waits "
        "for another one",
    )
