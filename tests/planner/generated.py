"""Random small planning problems in the thesis's shape, for property tests.

Each example is a generated domain and state, written as text in the thesis's
syntax and read, checked and compiled as :func:`cfgplan.problem.load` does
(:func:`tests.planner.problems.solve`; a test confirms it gives what ``load``
gives on files), so a failing example shrinks to a reproducer that can be
pasted into files and run with ``cfgplan plan``.

The domains have the thesis's shape: sensing functionalities (no inputs),
processing functionalities with one or two inputs, one action functionality
(no outputs), and three levels of methods (``do-task`` -> ``get-needJ`` ->
``get-dK``) with one to three versions each, preconditions over random facts
(``(hasK R1)``, ``(in R1 Room1)``, ``(broken R2)``, evals), local and global
channels, bandwidths and media. Now and then they also hold what a planner
gets wrong most easily: a channel from a method instance to itself (re-wired
at both ends into a cycle), a functionality whose output uses a variable its
own precondition binds (a localizer in a doorway: one binding per room), a
method ``:in`` that feeds two body items (fan-out), one channel written twice
with two bandwidths, and one call twice in a body. Beyond the thesis, they
hold ``(any ?r ?h)`` channels, devices, decimal weights and ``:cost``
(whose float sums tie only to the digits costs are ranked by), and
reliabilities of functionalities and media (7.2), which a ``reliability``
weight turns into costs; ``generated(uncertain=True)`` always has media, most
of them less than fully reliable, and that weight. Most are solvable, some
are not.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from hypothesis import strategies as st

from cfgplan.configuration.cost import Weights
from tests.planner.problems import Generated


@dataclass(frozen=True)
class Processor:
    """A processing functionality ``(pJ-P ?h ?r)`` running on ``?h`` that turns
    sensor data of ``?h`` and/or ``?r`` into ``(needJ ?r)``."""

    name: str
    inputs: tuple[tuple[int, str], ...]  # (sensor k, "?h" or "?r")


def _list(items: Sequence[str]) -> str:
    return "(" + " ".join(items) + ")"


def _bandwidth(draw: st.DrawFn) -> str:
    value = draw(st.sampled_from([None, None, 5, 10, 20, 50]))
    return "" if value is None else f" {value}"


def _functionality(
    name: str,
    *,
    inputs: Sequence[str] = (),
    outputs: Sequence[str] = (),
    precond: Sequence[str] = (),
    postcond: Sequence[str] = (),
    cost: float | None = None,
    reliability: float | None = None,
) -> str:
    parts = [f"(make-functionality :name '{name}"]
    if precond:
        parts.append(f"  :precond '{_list(precond)}")
    if inputs:
        parts.append(f"  :in '{_list(inputs)}")
    if outputs:
        parts.append(f"  :out '{_list(outputs)}")
    if postcond:
        parts.append(f"  :postcond '{_list(postcond)}")
    if cost is not None:
        parts.append(f"  :cost {cost}")
    if reliability is not None:
        parts.append(f"  :reliability {reliability}")
    return "\n".join(parts) + ")"


def _method(
    name: str,
    *,
    precond: list[str],
    inputs: list[str],
    outputs: list[str],
    channels: list[str],
    body: list[str],
    postcond: list[str],
) -> str:
    parts = [f"(make-config-method :name '{name}"]
    if precond:
        parts.append(f"  :precond '{_list(precond)}")
    if inputs:
        parts.append(f"  :in '{_list(inputs)}")
    if outputs:
        parts.append(f"  :out '{_list(outputs)}")
    if channels:
        parts.append(f"  :channels '{_list(channels)}")
    if postcond:
        parts.append(f"  :postcond '{_list(postcond)}")
    parts.append(f"  :body '{_list(body)}")
    return "\n".join(parts) + ")"


def _some(draw: st.DrawFn, options: list[str], most: int = 2) -> list[str]:
    """A few of ``options``, in their order."""
    chosen = draw(st.lists(st.sampled_from(options), max_size=most, unique=True))
    return [o for o in options if o in chosen]


FRACTIONS = [0.1, 0.2, 0.3, 0.7, 1.1, 2.5, 3]


@st.composite
def generated(draw: st.DrawFn, uncertain: bool = False) -> Generated:
    robots = [f"R{i}" for i in range(1, draw(st.integers(2, 4)) + 1)]
    sensors = list(range(1, draw(st.integers(1, 3)) + 1))
    needs = list(range(1, draw(st.integers(1, 2)) + 1))
    forms: list[str] = []

    # The world state: robots in rooms, some sensors, some broken.
    facts = [f"robot({r})" for r in robots]
    for r in robots:  # in one room, now and then in the doorway between both
        rooms = draw(st.sampled_from([[1], [2], [1], [2], [1, 2]]))
        facts += [f"in({r}, Room{n})" for n in rooms]
        battery = draw(st.sampled_from([None, 5, 50, 50]))
        if battery is not None:
            facts.append(f"battery({r}, {battery})")
    for k in sensors:
        facts += [f"has{k}({r})" for r in robots if draw(st.integers(0, 4)) > 0]
    facts += [f"broken({r})" for r in robots if draw(st.integers(0, 4)) == 0]
    facts += [f"device({r})" for r in robots if draw(st.integers(0, 5)) == 0]  # weighted apart
    if uncertain or draw(st.booleans()):  # media: between every two robots, or a few links
        pairs = [(a, b) for a in robots for b in robots if a != b]
        if draw(st.booleans()):
            pairs = draw(st.lists(st.sampled_from(pairs), max_size=6))
        for a, b in pairs:
            capacity = draw(st.sampled_from([0, 10, 30, 100, 100]))
            unsaid = [""] if uncertain else ["", ""]
            reliability = draw(st.sampled_from([*unsaid, ", 0.9", ", 0.5"]))  # 7.2
            facts.append(f"medium(link, {a}, {b}, {capacity}{reliability})")

    # Sensing resources and filters.
    for k in sensors:
        guard = draw(st.sampled_from(["", "has", "has", "room", "battery"]))
        forms.append(
            _functionality(
                f"(sens{k} ?r)",
                outputs=[f"(d{k} ?r)"],
                precond={
                    "": [],
                    "has": [f"(has{k} ?r)"],
                    "room": [f"(has{k} ?r)", "(in ?r ?room)"],  # a binding per room
                    "battery": ["(battery ?r ?b)", "(eval (> ?b 20))"],
                }[guard],
                postcond=["(watched ?room)"] if guard == "room" else [],
                cost=draw(st.sampled_from([None, None, None, 0, 2, 0.3])),
                reliability=draw(st.sampled_from([None, None, 0.8, 0.95])),
            )
        )
        forms.append(_functionality(f"(filt{k} ?r)", inputs=[f"(d{k} ?r)"], outputs=[f"(d{k} ?r)"]))

    # Processing functionalities: one or two per need.
    processors: dict[int, list[Processor]] = {}
    wrappers: dict[str, str] = {}
    for j in needs:
        processors[j] = []
        for p in range(1, draw(st.integers(1, 2)) + 1):
            ks = draw(st.lists(st.sampled_from(sensors), min_size=1, max_size=2, unique=True))
            inputs = tuple((k, draw(st.sampled_from(["?h", "?r"]))) for k in ks)
            proc = Processor(f"p{j}-{p}", inputs)
            processors[j].append(proc)
            forms.append(
                _functionality(
                    f"({proc.name} ?h ?r)",
                    inputs=[f"(d{k} {who})" for k, who in inputs],
                    outputs=[f"(need{j} ?r)"],
                    precond=draw(
                        st.sampled_from(
                            [
                                [],
                                ["(robot ?h)"],
                                ["(not (broken ?h))"],
                                ["(battery ?h ?b)", "(eval (>= ?b 10))"],
                            ]
                        )
                    ),
                    cost=draw(st.sampled_from([None, None, None, 1, 3, 0.7])),
                )
            )
            if draw(st.booleans()):  # a method around it, fed through :in ports
                wrappers[proc.name] = f"w{j}-{p}"
                forms.append(
                    _method(
                        f"(w{j}-{p} ?h ?r)",
                        precond=[],
                        inputs=[f"(?p (d{k} {who}))" for k, who in inputs],
                        outputs=[f"(?p (need{j} ?r))"],
                        channels=[],
                        body=[f"(?p ({proc.name} ?h ?r))"],
                        postcond=[],
                    )
                )

    # The action resource; sometimes it also needs the robot's position, which a
    # localizer produces under the binding of its own precondition (in ?r ?room):
    # a robot in the doorway gets one binding per room, each with other outputs.
    located = draw(st.integers(0, 3)) == 0
    if located:
        forms.append(
            _functionality("(loc ?r)", precond=["(in ?r ?room)"], outputs=["(pos ?r ?room)"])
        )
    forms.append(
        _functionality(
            "(act ?r)",
            inputs=[f"(need{j} ?r)" for j in needs] + (["(pos ?r ?where)"] if located else []),
            precond=_some(draw, ["(robot ?r)", "(not (broken ?r))"], 1)
            + (["(in ?r ?where)"] if located else []),
            postcond=_some(draw, ["(done ?r)", "(not (idle ?r))"]),
        )
    )
    # A monitor that listens to need 1 beside the action (fan-out through :in).
    forms.append(_functionality("(mon ?r)", inputs=["(need1 ?r)"]))

    # Level 0: get-dK, sensor alone or sensor and filter; now and then a version
    # whose filter, behind a method with :in and :out on one descriptor, gets a
    # channel to itself: re-wired at both ends it is a cycle (4.5 3d, 5.1).
    for k in sensors:
        versions = []
        if draw(st.integers(0, 5)) == 0:
            forms.append(
                _method(
                    f"(loop{k} ?x)",
                    precond=[],
                    inputs=[f"(?g (d{k} ?x))"],
                    outputs=[f"(?g (d{k} ?x))"],
                    channels=[],
                    body=[f"(?g (filt{k} ?x))"],
                    postcond=[],
                )
            )
            versions.append(
                _method(
                    f"(get-d{k} ?x)",
                    precond=[],
                    inputs=[],
                    outputs=[f"(?f2 (d{k} ?x))"],
                    channels=[
                        f"((local ?x) ?f1 ?f2 (d{k} ?x))",
                        f"((local ?x) ?f2 ?f2 (d{k} ?x))",
                    ],
                    body=[f"(?f1 (sens{k} ?x))", f"(?f2 (loop{k} ?x))"],
                    postcond=[],
                )
            )
        for filtered in draw(st.lists(st.booleans(), min_size=1, max_size=2)):
            precond = _some(draw, [f"(has{k} ?x)", "(robot ?x)", "(not (broken ?x))"])
            if filtered:
                versions.append(
                    _method(
                        f"(get-d{k} ?x)",
                        precond=precond,
                        inputs=[],
                        outputs=[f"(?f2 (d{k} ?x){_bandwidth(draw)})"],
                        channels=[f"((local ?x) ?f1 ?f2 (d{k} ?x))"],
                        body=[f"(?f1 (sens{k} ?x))", f"(?f2 (filt{k} ?x))"],
                        postcond=[],
                    )
                )
            else:
                versions.append(
                    _method(
                        f"(get-d{k} ?x)",
                        precond=precond,
                        inputs=[],
                        outputs=[f"(?f1 (d{k} ?x))"],
                        channels=[],
                        body=[f"(?f1 (sens{k} ?x))"],
                        postcond=[],
                    )
                )
        forms.extend(versions)

    # Level 1: get-needJ ?h ?r, a processor on ?h fed from ?h (local) or ?r (global).
    for j in needs:
        versions = []
        for _ in range(draw(st.integers(1, 3))):
            proc = draw(st.sampled_from(processors[j]))
            precond = _some(
                draw,
                [
                    "(robot ?h)",
                    "(in ?h ?room)",
                    f"(has{draw(st.sampled_from(sensors))} ?h)",
                    "(not (broken ?h))",
                    "(eval (not (eql (quote ?h) (quote ?r))))",
                ],
                3,
            )
            if "(in ?h ?room)" in precond:
                precond.insert(precond.index("(in ?h ?room)") + 1, "(in ?r ?room)")
            wrapper = wrappers.get(proc.name)
            if wrapper is not None and draw(st.booleans()):
                body = [f"(?f0 ({wrapper} ?h ?r))"]
            else:
                body = [f"(?f0 ({proc.name} ?h ?r))"]
            channels = []
            for i, (k, who) in enumerate(proc.inputs, start=1):
                direct = draw(st.integers(0, 3)) == 0
                body.append(f"(?f{i} ({'sens' if direct else 'get-d'}{k} {who}))")
                if who == "?h":
                    channels.append(f"((local ?h) ?f{i} ?f0 (d{k} ?h))")
                elif draw(st.integers(0, 7)) == 0:  # a slip: only right when ?h is ?r
                    channels.append(f"((local ?h) ?f{i} ?f0 (d{k} ?r))")
                elif draw(st.integers(0, 3)) == 0:  # local when ?h is ?r, else global
                    channels.append(f"((any ?r ?h) ?f{i} ?f0 (d{k} ?r){_bandwidth(draw)})")
                else:
                    channels.append(f"((global ?r ?h) ?f{i} ?f0 (d{k} ?r){_bandwidth(draw)})")
            versions.append(
                _method(
                    f"(get-need{j} ?h ?r)",
                    precond=precond,
                    inputs=[],
                    outputs=[f"(?f0 (need{j} ?r){_bandwidth(draw)})"],
                    channels=channels,
                    body=body,
                    postcond=_some(draw, ["(busy ?h)", f"(got{j} ?r)"], 1),
                )
            )
        if draw(st.integers(0, 3)) == 0:  # a repeated version: repeated derivations
            versions.append(draw(st.sampled_from(versions)))
        forms.extend(versions)

    # The action wrapped in a method with :in ports, sometimes.
    wrapped = not located and draw(st.booleans())  # do-act has no :in for the position
    if wrapped:
        for _ in range(draw(st.integers(1, 2))):
            monitored = draw(st.integers(0, 2)) == 0  # need1 fans out to a monitor too
            forms.append(
                _method(
                    "(do-act ?r)",
                    precond=_some(draw, ["(robot ?r)", "(not (idle ?r))"], 1),
                    inputs=[f"(?a (need{j} ?r))" for j in needs]
                    + (["(?m (need1 ?r))"] if monitored else []),
                    outputs=[],
                    channels=[],
                    body=["(?a (act ?r))"] + (["(?m (mon ?r))"] if monitored else []),
                    postcond=[],
                )
            )

    # Level 2: do-task ?r, each need from ?r itself or from a helper ?h.
    for _ in range(draw(st.integers(1, 3))):
        helped = [draw(st.booleans()) for _ in needs]
        precond = _some(draw, ["(robot ?r)", "(not (broken ?r))"], 1)
        if any(helped):
            precond.append("(robot ?h)")
            precond += _some(
                draw,
                [
                    "(in ?h ?room)",
                    "(not (broken ?h))",
                    "(eval (not (eql (quote ?h) (quote ?r))))",
                ],
            )
            if "(in ?h ?room)" in precond:
                precond.insert(precond.index("(in ?h ?room)") + 1, "(in ?r ?room)")
        body = [f"(?f0 ({'do-act' if wrapped else 'act'} ?r))"]
        channels = []
        for j, help_ in zip(needs, helped, strict=True):
            body.append(f"(?f{j} (get-need{j} {'?h' if help_ else '?r'} ?r))")
            if help_:
                channel = f"((global ?h ?r) ?f{j} ?f0 (need{j} ?r)"
                channels.append(f"{channel}{_bandwidth(draw)})")
            else:
                channel = f"((local ?r) ?f{j} ?f0 (need{j} ?r)"
                channels.append(f"{channel})")
            if draw(st.integers(0, 5)) == 0:  # the same channel again, other bandwidth
                channels.append(f"{channel} {draw(st.sampled_from([1, 7, 40]))})")
        if draw(st.integers(0, 4)) == 0:  # the same call twice in one body
            twice = draw(st.sampled_from([f"(get-d{sensors[0]} ?r)", f"(sens{sensors[0]} ?r)"]))
            body += [f"(?t1 {twice})", f"(?t2 {twice})"]
        if located:
            precond.append("(in ?r ?where)")
            body.append("(?fl (loc ?r))")
            channels.append("((local ?r) ?fl ?f0 (pos ?r ?where))")
        forms.append(
            _method(
                "(do-task ?r)",
                precond=precond,
                inputs=[],
                outputs=[],
                channels=channels,
                body=body,
                postcond=[],
            )
        )

    reliable = st.builds(  # reliability adds logarithms: costs without a unit
        Weights, robot=st.integers(0, 10), reliability=st.sampled_from([1, 10, 0.3])
    )
    weights = draw(
        reliable
        if uncertain
        else st.one_of(
            st.just(Weights()),
            st.builds(
                Weights,
                robot=st.integers(0, 10),
                global_=st.integers(0, 3),
                local=st.integers(0, 2),
                functionality=st.integers(0, 2),
                device=st.integers(0, 10),
            ),
            st.builds(  # decimal weights: float sums of equal costs may differ in the last bit
                Weights,
                robot=st.sampled_from(FRACTIONS),
                global_=st.sampled_from(FRACTIONS),
                local=st.sampled_from(FRACTIONS),
                functionality=st.sampled_from(FRACTIONS),
                device=st.sampled_from(FRACTIONS),
            ),
            reliable,
        )
    )
    state = f"(state {', '.join(facts)})\n\n(goal (do-task R1))\n"
    return Generated("\n".join(forms) + "\n", state, weights)
