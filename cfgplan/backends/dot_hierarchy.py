"""The method hierarchy of a goal in DOT, drawn like the thesis's Fig. 4.4.

Starting from the goal method's schema (``do-cross-door(r, d)``), each method
points to the items of its body with the method's parameters replaced by the
caller's arguments, as the figure prints them (``get-door-info(rh1, r, d)`` ->
``get-door-info(rh1, d)`` -> ``camera(rh1)``). Methods are grey boxes,
functionalities white ones. A method with several versions gets one small
``version k`` node per version, showing that version's preconditions, and its
body hangs from there. Functionalities are leaves drawn under each method
that uses them, like the figure (``camera(rh1)`` appears three times); a
method call drawn once is not drawn again: every other caller points to the
one box, so a hierarchy that uses one method in many places (build-wall's
``get-block-data(robserv, b, w)``) stays readable. A method already being
expanded higher up the same branch is drawn dashed, with a dashed arrow back
to it, and is not expanded again, so recursive methods end.

Node ids are the paths of body labels from the root (``goal.f1.v2.f3``), so the
DOT source is the same on every run.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from cfgplan.backends.dot import call, dot_text, html_text, new_graph, term
from cfgplan.diagnostics import error
from cfgplan.ir.model import SExpr, is_variable
from cfgplan.notation import sexpr_text
from cfgplan.planner.task import MethodSchema, Task, TestKind

METHOD = {"fillcolor": "gray80"}
FUNCTIONALITY = {"fillcolor": "white"}
VERSION = {"shape": "box", "style": "rounded", "fontsize": "8", "margin": "0.06,0.03"}
UNKNOWN = {"fillcolor": "white", "style": "dashed", "color": "red"}
MAX_NODES = 2000

Call = tuple[str, ...]


@dataclass
class _Builder:
    task: Task
    graph: Any
    max_nodes: int
    count: int = 0
    has_versions: bool = False
    path: dict[tuple[str, int], str] = field(default_factory=dict)  # method -> node id
    drawn: dict[Call, str] = field(default_factory=dict)  # method call -> its one node id

    def add(self, node_id: str, label: str, **attrs: str) -> None:
        self.count += 1
        if self.count > self.max_nodes:
            raise error(
                f"the method hierarchy has more than {self.max_nodes} nodes; "
                "it is too large to draw",
                hint="draw the hierarchy of a method lower down with --goal",
            )
        self.graph.node(node_id, label, **attrs)

    def expand(self, node_id: str, goal: tuple[str, ...]) -> None:
        """Draw the method ``goal`` and everything below it, depth first.

        Each method's expansion is a generator that yields the methods of its
        body to expand next; this loop runs them on an explicit stack, so a
        hierarchy thousands of levels deep needs no Python recursion."""
        stack = [self._versions(node_id, goal)]
        while stack:
            below = next(stack[-1], None)
            if below is None:
                stack.pop()
            else:
                stack.append(self._versions(*below))

    def _versions(self, node_id: str, goal: tuple[str, ...]) -> Iterator[tuple[str, Call]]:
        """Draw the bodies of every version of the method ``goal``, yielding each
        body method (node id and call) to be expanded before the next item."""
        signature = (goal[0], len(goal) - 1)
        versions = self.task.methods[signature]
        self.path[signature] = node_id
        for method in versions:
            parent = node_id
            env = substitution(method, goal[1:])
            if len(versions) > 1:
                self.has_versions = True
                parent = f"{node_id}.v{method.version}"
                self.add(parent, version_label(method, env), **VERSION)
                self.graph.edge(node_id, parent, style="dashed", arrowhead="none")
            for label, pattern in method.body:
                child = (pattern[0], *(env.get(a, a) for a in pattern[1:]))
                child_id = f"{parent}.{label.lstrip('?')}"
                if self.item(child_id, parent, child):
                    yield child_id, child
        del self.path[signature]

    def item(self, node_id: str, parent: str, item: Call) -> bool:
        """Draw one body item: a functionality, a method, or a recursion; True
        for a method, whose body is to be drawn below it."""
        signature = (item[0], len(item) - 1)
        text = dot_text(call(item[0], item[1:]))
        if signature in self.path:
            self.add(node_id, f"{text}\\n(recursive)", style="filled,dashed", **METHOD)
            self.graph.edge(parent, node_id)
            self.graph.edge(
                node_id, self.path[signature], style="dashed", constraint="false", label="recurs"
            )
        elif item in self.drawn:
            self.graph.edge(parent, self.drawn[item])
        elif signature in self.task.methods:
            self.add(node_id, text, **METHOD)
            self.graph.edge(parent, node_id)
            self.drawn[item] = node_id
            return True
        elif signature in self.task.functionalities:
            self.add(node_id, text, **FUNCTIONALITY)
            self.graph.edge(parent, node_id)
        else:
            self.add(node_id, f"{text}\\n(undefined)", **UNKNOWN)
            self.graph.edge(parent, node_id)
        return False


def substitution(method: MethodSchema, args: Sequence[str]) -> dict[str, str]:
    """Parameters to the caller's arguments; other variables keep their names,
    primed (``rh1'``) when the caller already uses that name."""
    env = dict(zip(method.params, args, strict=True))
    taken = {a for a in args if is_variable(a)}
    for var in _variables(method):
        if var in env:
            continue
        name = var
        while name in taken:
            name += "'"
        env[var] = name
        taken.add(name)
    return env


def _variables(method: MethodSchema) -> list[str]:
    """The variables of a method's body and preconditions, in order of appearance."""
    found: dict[str, None] = {}
    for _, pattern in method.body:
        found.update(dict.fromkeys(a for a in pattern[1:] if is_variable(a)))
    for test in method.tests:
        found.update(dict.fromkeys(test.variables()))
    return list(found)


def version_label(method: MethodSchema, env: dict[str, str]) -> str:
    """``version 2`` and its preconditions, one a line: what tells versions apart."""
    lines = [f"version {method.version}"]
    for test in method.tests:
        if test.kind is TestKind.EVAL:
            lines.append("eval " + _sexpr(test.expr, env))
        else:
            atom = call(test.pattern[0], [env.get(a, a) for a in test.pattern[1:]])
            lines.append(f"not {atom}" if test.kind is TestKind.NOT else atom)
    return "<" + "<BR/>".join(html_text(line) for line in lines) + ">"


def _sexpr(expr: SExpr, env: dict[str, str]) -> str:
    """``expr`` with the variables of ``env`` replaced, as the figures print terms."""
    return sexpr_text(expr, lambda leaf: term(env.get(str(leaf), str(leaf))))


def hierarchy_graph(task: Task, goal: Sequence[str], *, max_nodes: int = MAX_NODES) -> Any:
    """The ``graphviz.Digraph`` of the methods and functionalities below the
    method of ``goal`` (name and arity; its arguments are not used)."""
    signature = (goal[0], len(goal) - 1)
    versions = task.methods.get(signature)
    if not versions:
        raise error(f"{goal[0]} with {signature[1]} argument(s) is not a method of the domain")
    root = (goal[0], *versions[0].params)
    text = call(root[0], root[1:])
    graph = new_graph("hierarchy", f"Methods (grey) and functionalities (white) for {text}")
    builder = _Builder(task, graph, max_nodes)
    builder.add("goal", dot_text(text), **METHOD)
    builder.drawn[root] = "goal"
    builder.expand("goal", root)
    _legend(graph, builder.has_versions)
    return graph


def _legend(graph: Any, versions: bool) -> None:
    with graph.subgraph(name="cluster_legend") as legend:
        legend.attr(label="Legend", style="rounded", color="gray60", fontsize="11")
        legend.node_attr.update(fontsize="9", margin="0.08,0.04", height="0.3")
        legend.node("legend_method", "method", **METHOD)
        legend.node("legend_functionality", "functionality", **FUNCTIONALITY)
        legend.edge("legend_method", "legend_functionality", style="invis")
        if versions:
            legend.node("legend_version", "version k: its preconditions", **VERSION)
            legend.edge("legend_functionality", "legend_version", style="invis")


def hierarchy_dot(task: Task, goal: Sequence[str], *, max_nodes: int = MAX_NODES) -> str:
    """DOT source of :func:`hierarchy_graph`."""
    return str(hierarchy_graph(task, goal, max_nodes=max_nodes).source)
