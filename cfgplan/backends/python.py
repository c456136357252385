"""Translating individual configurations into Python modules (5.3, with cfgplan.runtime).

The thesis generates LISP (5.3); this backend does the same job in Python.
A robot's module has a ``configure(robot)`` function that creates the
robot's channels, named ``ch_1`` .. ``ch_n`` as CH-1 .. CH-n (the ``LET``),
and the wrappers of its functionalities (5.2.1), and returns the *cycle*
(the ``LAMBDA``): one call per functionality in sorted order, passing one
entry per ``:in`` descriptor and one list of channels per ``:out``
descriptor, as the LISP call does. An input fed by several channels gets a
list, an input without channel ``None``; a functionality whose operator has
a ``:freq`` (3.2) gets it (``freq=10``). Run as a script, the module runs that
robot in its own process, its global channels over Zenoh to the other
robots' processes (``python emil.py --impl IMPL --listen tcp/0.0.0.0:7447``;
the options are those of :func:`cfgplan.runtime.robot_main`).

A ``run_all.py`` is emitted too: it loads every robot's module and runs them
together in one process, joined by the in-process transport. The text is
deterministic: no dates, no paths.

Names from the input reach the code only escaped: in string literals
(:func:`py_str`) and docstrings every backslash, quote and unsafe character
(control, format, line separator) is escaped, in comments unsafe characters
are; identifiers are made of labels and ASCII letters only. So the module
compiles for any name the reader accepts (``D\\x1``, a NUL, a BEL).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import TYPE_CHECKING

from cfgplan.backends.wiring import Call, RobotPart
from cfgplan.diagnostics import escape_char, is_unsafe, printable
from cfgplan.notation import call_text
from cfgplan.safe_names import safe_stem

if TYPE_CHECKING:
    from cfgplan.security.identity import ProblemId

__all__ = ["module_name", "py_str", "run_all", "to_python"]

WIDTH = 100


def module_name(robot: str) -> str:
    """The file a robot's module is written to on its own: ``emil.py`` for Emil
    (without ``.py``); :attr:`RobotPart.stem` also keeps robots apart whose
    names differ only in case."""
    return safe_stem(robot)


def _doc(text: str) -> str:
    """``text`` for inside a double-quoted literal or docstring."""
    out = []
    for char in text:
        if char in '\\"':
            out.append("\\" + char)
        elif is_unsafe(char):
            out.append(escape_char(char))
        else:
            out.append(char)
    return "".join(out)


def py_str(text: str) -> str:
    """A Python string literal holding exactly ``text``."""
    return '"' + _doc(text) + '"'


_str = py_str  # the name the code below has always used


def _comment(text: str) -> str:
    """``text`` for a ``#`` comment: nothing in it can end the line."""
    return printable(text)


def _tuple(items: Sequence[str]) -> str:
    inner = ", ".join(_str(x) for x in items)
    return f"({inner},)" if len(items) == 1 else f"({inner})"


def _number(x: float) -> str:
    """``10`` rather than ``10.0``; exact otherwise."""
    return str(int(x)) if float(x).is_integer() else repr(float(x))


def _channel(index: int) -> str:
    return f"ch_{index + 1}"


def _wrapper(call: Call) -> str:
    f = call.functionality
    return f"{f.label.lower()}_{re.sub(r'[^0-9a-zA-Z]+', '_', f.name).strip('_').lower()}"


def _input(channels: Sequence[int]) -> str:
    if not channels:
        return "None"
    if len(channels) == 1:
        return _channel(channels[0])
    return "[" + ", ".join(_channel(i) for i in channels) + "]"


def _outputs(outputs: Sequence[Sequence[int]]) -> str:
    return "[" + ", ".join("[" + ", ".join(_channel(i) for i in o) + "]" for o in outputs) + "]"


def _signature(call: Call) -> list[str]:
    """Comment lines: the functionality, its inputs and outputs."""
    ins = ", ".join(call_text(d) for d in call.input_data) or "no input"
    outs = ", ".join(call_text(d) for d in call.output_data) or "no output"
    name = _comment(str(call.functionality))
    ins, outs = _comment(ins), _comment(outs)
    line = f"    # {name}: {ins} -> {outs}"
    if len(line) <= WIDTH:
        return [line]
    return [f"    # {name}", f"    #   in: {ins}", f"    #   out: {outs}"]


def _statement(indent: str, head: str, args: str) -> list[str]:
    """``head(args)`` on one line, or with ``args`` on a line of their own."""
    line = f"{indent}{head}({args})"
    if len(line) <= WIDTH:
        return [line]
    return [f"{indent}{head}(", f"{indent}    {args}", f"{indent})"]


def to_python(part: RobotPart, title: str, problem: ProblemId | None = None) -> str:
    """The module of one robot; ``title`` says which configuration it is part of;
    ``problem``, the problem it was planned for, is announced to the society and
    checked against the other robots' (:mod:`cfgplan.security.identity`)."""
    robot = part.robot
    shown = _doc(robot)
    ind = part.individual
    lines = [
        f'"""{shown}\'s part of a configuration, as Python (thesis 5.3; cfgplan emit).',
        "",
        f"{_doc(title)}.",
        "The individual configuration (5.4):",
        "",
        *("    " + _doc(x) for x in ind.text().splitlines()),
        "",
        f"configure() creates {shown}'s channels (the LET of 5.3) and returns the cycle",
        "(the LAMBDA): one call to each functionality, in sorted order (5.1). Run this",
        "robot in a process of its own, its global channels over Zenoh (5.2.2):",
        "",
        f"    python {part.stem}.py --impl IMPL [--listen ENDPOINT] [--connect ENDPOINT]",
        "        [--society NAME] [--rate HZ] [--cycles N] [--duration S] [--trace FILE]",
        "",
        "IMPL is a module name or a .py file declaring the implementations with",
        "@functionality (cfgplan.runtime); --help lists every option. run_all.py runs",
        "every robot of the configuration in one process.",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "from cfgplan.runtime import Cycle, Robot, robot_main",
        *(["from cfgplan.security.identity import ProblemId"] if problem else []),
        "",
        f"ROBOT = {_str(robot)}",
        *(_problem(problem) if problem else []),
        "",
        "",
        "def configure(robot: Robot) -> Cycle:",
        f'    """{shown}\'s channels and functionalities; returns one cycle."""',
    ]
    if ind.channels:
        lines.append(f"    # LET: the channels CH-1 .. CH-{len(ind.channels)} (5.2.2, 5.3)")
    for i, ch in enumerate(ind.channels):
        data = _tuple(ch.data)
        ends = f"{_str(ch.source)}, {_str(ch.target)}, {data}"
        if ch.kind == "local":
            lines += _statement("    ", f"{_channel(i)} = robot.local_channel", ends)
        else:
            other = ch.target_robot if ch.source_robot == robot else ch.source_robot
            lines += _statement(
                "    ", f"{_channel(i)} = robot.global_channel", f"{_str(other)}, {ends}"
            )
    lines.append("    # the wrappers of the functionalities (5.2.1), in sorted order")
    for call in part.calls:
        f = call.functionality
        objects = f", {_tuple(call.objects)}" if call.objects else ""
        if call.freq is not None:
            objects += f", freq={_number(call.freq)}"
        objects += f", inputs={len(call.inputs)}"
        lines += _signature(call)
        head = f"{_wrapper(call)} = robot.wrapper"
        lines += _statement("    ", head, f"{_str(f.label)}, {_str(f.name)}{objects}")
    lines += [
        "",
        "    def cycle() -> None:",
        '        """LAMBDA: each functionality once, in sorted order."""',
    ]
    for call in part.calls:
        inputs = ", ".join(_input(x) for x in call.inputs)
        lines += _statement(
            "        ", _wrapper(call), f"inputs=[{inputs}], outputs={_outputs(call.outputs)}"
        )
    if not part.calls:
        lines.append("        pass")
    lines += [
        "",
        "    return cycle",
        "",
        "",
        'if __name__ == "__main__":',
        "    raise SystemExit(robot_main(ROBOT, configure"
        + (", problem=PROBLEM))" if problem else "))"),
    ]
    return "\n".join(lines) + "\n"


def _problem(problem: ProblemId) -> list[str]:
    """``PROBLEM = ProblemId(...)``: what the robot announces."""
    args = f"{_str(problem.fingerprint)}, {_str(problem.about)}"
    return _statement("", "PROBLEM = ProblemId", args)


def run_all(parts: Sequence[RobotPart], title: str) -> str:
    """``run_all.py``: every robot of the configuration in one process."""
    robots = [p.robot for p in parts]
    files = ", ".join(f"{p.stem}.py" for p in parts)
    entries = [f"    ({_str(p.robot)}, {_str(p.stem + '.py')})," for p in parts]
    lines = [
        '"""All robots of a configuration in one process (thesis 5.3; cfgplan emit).',
        "",
        f"{_doc(title)}: {_doc(', '.join(robots))}.",
        f"Each robot's module ({files}) creates its channels and its cycle;",
        "here their global channels are joined by an in-process transport and the",
        "robots run one cycle each in turn. Run:",
        "",
        "    python run_all.py --impl IMPL [--rate HZ] [--cycles N] [--duration S] [--trace FILE]",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "from pathlib import Path",
        "",
        "from cfgplan.runtime import Configure, load_module, society_main",
        "",
        "HERE = Path(__file__).resolve().parent",
        "ROBOTS = (",
        *entries,
        ")",
        "",
        "",
        "def programs() -> list[tuple[str, Configure]]:",
        '    """Each robot and its configure function, from the modules beside this file."""',
        "    return [(robot, load_module(HERE / file).configure) for robot, file in ROBOTS]",
        "",
        "",
        'if __name__ == "__main__":',
        "    raise SystemExit(society_main(programs()))",
    ]
    return "\n".join(lines) + "\n"
