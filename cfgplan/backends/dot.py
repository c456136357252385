"""Configuration diagrams in DOT, drawn like the thesis's Fig. 4.3, 6.4, 6.8 and 6.11.

A box per functionality shows its name in bold and ``label : (args)`` below,
laid out as the figures do (``camera`` / ``F8 : (Emil)``) but with the names'
case kept as written: names are case-sensitive (docs/reference/language.md), and the figures'
capitals would turn ``Emil`` and ``EMIL`` into one robot. Each robot gets one
fill colour and one cluster; global channels are bold black arrows, local
channels thin grey ones (the captions of Fig. 4.3 and 6.11), each labelled with
its data and, when declared, its bandwidth. A local channel is drawn inside its
robot's cluster, so that Graphviz keeps its label there too. A legend names the
colours and edge styles.

Only DOT source is built here (the ``graphviz`` package needs no binary for
that); :mod:`cfgplan.backends.render` lays it out. The source is deterministic:
node ids are the functionality labels, everything comes in list order.

Names from the input enter DOT strings only through :func:`dot_text` and
HTML-like labels only through :func:`html_text`: a backslash, a NUL or an
ESC in a robot's name cannot break the DOT source.
"""

from __future__ import annotations

import html
import itertools
from collections.abc import Sequence
from typing import Any

import graphviz  # type: ignore[import-untyped]

from cfgplan.configuration.cost import fmt
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.diagnostics import printable
from cfgplan.notation import call_text

FONT = "Helvetica"
ROBOT_COLOURS = (
    "white",
    "gray80",
    "lightblue",
    "palegreen",
    "lightgoldenrod1",
    "lightpink",
    "plum1",
    "lightsalmon",
)
"""Fill colours by robot rank: white then grey as in Fig. 4.3, then pastels."""

GLOBAL_EDGE = {"style": "bold", "color": "black", "fontcolor": "black", "penwidth": "2"}
LOCAL_EDGE = {"style": "solid", "color": "gray55", "fontcolor": "gray35", "penwidth": "1"}


def dot_text(text: str) -> str:
    """``text`` for a DOT string shown as it is: unsafe characters escaped as
    ``\\x00`` text, every backslash doubled so that none starts a DOT escape
    (``\\n``) or escapes the closing quote."""
    return printable(text).replace("\\", "\\\\")


def html_text(text: str) -> str:
    """``text`` for an HTML-like label: unsafe characters escaped, then ``<&>"``."""
    return html.escape(printable(text))


def term(t: str) -> str:
    """A term as the figures print a schema's variables: ``?rh1`` -> ``rh1``."""
    return t[1:] if t.startswith("?") else t


def call(name: str, args: Sequence[str]) -> str:
    """``get-door-info(rh1, r, d)``: the thesis's notation for a call."""
    return call_text((name, *(term(a) for a in args)))


def new_graph(name: str, title: str = "") -> Any:
    """A ``graphviz.Digraph`` with the common look: Helvetica, boxes, title on top."""
    graph_attr = {"fontname": FONT, "nodesep": "0.35", "ranksep": "0.55"}
    if title:
        graph_attr.update({"label": dot_text(title), "labelloc": "t", "fontsize": "14"})
    return graphviz.Digraph(
        name=name,
        graph_attr=graph_attr,
        node_attr={"fontname": FONT, "fontsize": "11", "shape": "box", "style": "filled"},
        edge_attr={"fontname": FONT, "fontsize": "9", "arrowsize": "0.7"},
    )


def robot_order(config: Configuration, first: Sequence[str] = ()) -> list[str]:
    """The configuration's robots, those named in ``first`` (e.g. the goal's
    arguments) ahead, so the goal's robot is white as in Fig. 4.3 and 6.11."""
    robots = config.agents
    ahead = [r for r in dict.fromkeys(first) if r in robots]
    return ahead + [r for r in robots if r not in ahead]


def robot_colours(robots: Sequence[str]) -> dict[str, str]:
    """One fill colour per robot, cycling through :data:`ROBOT_COLOURS`."""
    return {r: ROBOT_COLOURS[i % len(ROBOT_COLOURS)] for i, r in enumerate(robots)}


def functionality_label(f: FunctionalityInstance) -> str:
    """``<<B>camera</B><BR/>F8 : (Emil)>``: the box text of Fig. 4.3 as an HTML-like label."""
    name = html_text(f.name)
    where = html_text(f"{f.label} : ({' '.join(f.args)})")
    return f"<<B>{name}</B><BR/>{where}>"


def channel_label(ch: Channel) -> str:
    """``image(Emil)``, with ``bandwidth 20`` on a second line when declared."""
    data = dot_text(f"{ch.data[0]}({', '.join(ch.data[1:])})")
    if ch.bandwidth is not None:
        data += f"\\nbandwidth {fmt(ch.bandwidth)}"
    return data


def configuration_graph(
    config: Configuration, *, title: str = "", first: Sequence[str] = ()
) -> Any:
    """The ``graphviz.Digraph`` of one configuration (Fig. 4.3 style).

    ``first`` names robots to colour first (the goal's arguments).
    """
    robots = robot_order(config, first)
    colours = robot_colours(robots)
    layer = layers(config)
    wired = {(ch.source, ch.target) for ch in config.channels}
    graph = new_graph("configuration", title)
    for index, robot in enumerate(robots):
        with graph.subgraph(name=f"cluster_{index}_{dot_text(robot)}") as cluster:
            cluster.attr(
                label=dot_text(robot), style="rounded,dashed", color="gray40", fontsize="12"
            )
            mine = [f for f in config.functionalities if f.robot == robot]
            for f in mine:
                cluster.node(f.label, functionality_label(f), fillcolor=colours[robot])
            _keep_layers(cluster, [f.label for f in mine], layer, wired)
            for ch in config.channels:
                if _inside(ch) and ch.source_robot == robot:
                    cluster.edge(ch.source, ch.target, channel_label(ch), **LOCAL_EDGE)
    for ch in config.channels:
        if not _inside(ch):
            style = GLOBAL_EDGE if ch.kind == "global" else LOCAL_EDGE
            graph.edge(ch.source, ch.target, channel_label(ch), **style)
    _legend(graph, robots, colours)
    return graph


def _inside(ch: Channel) -> bool:
    """Whether ``ch`` is drawn inside its robot's cluster: a local channel."""
    return ch.kind == "local" and ch.source_robot == ch.target_robot


def layers(config: Configuration) -> dict[str, int]:
    """Each functionality's layer: the longest channel path reaching it (a
    channel closing a cycle is ignored), so sensors sit on top as in Fig. 4.3."""
    succ: dict[str, list[str]] = {f.label: [] for f in config.functionalities}
    for ch in config.channels:
        if ch.source != ch.target:
            succ[ch.source].append(ch.target)
    order: list[str] = []  # reverse post-order of a DFS in list order
    state: dict[str, int] = {}  # 1 on the DFS stack, 2 finished
    kept: dict[str, list[str]] = {label: [] for label in succ}
    for start in succ:
        if start in state:
            continue
        state[start] = 1
        stack = [(start, iter(succ[start]))]
        while stack:
            node, todo = stack[-1]
            nxt = next(todo, None)
            if nxt is None:
                state[node] = 2
                order.append(node)
                stack.pop()
            elif state.get(nxt) != 1:  # not a back edge
                kept[node].append(nxt)
                if nxt not in state:
                    state[nxt] = 1
                    stack.append((nxt, iter(succ[nxt])))
    layer = dict.fromkeys(succ, 0)
    for node in reversed(order):
        for nxt in kept[node]:
            layer[nxt] = max(layer[nxt], layer[node] + 1)
    return layer


def _keep_layers(
    cluster: Any, labels: Sequence[str], layer: dict[str, int], wired: set[tuple[str, str]]
) -> None:
    """Invisible, weightless edges that keep a robot's boxes on their layers:
    without them dot ranks a cluster on its own edges only, and a sensor such
    as Pippi's compass would sink to the bottom beside her cross-door. None is
    added where a channel already links the two boxes one layer apart."""
    firsts: dict[int, str] = {}
    for label in labels:
        firsts.setdefault(layer[label], label)
    steps = sorted(firsts.items())
    for (low, tail), (high, head) in itertools.pairwise(steps):
        if high - low > 1 or (tail, head) not in wired:
            cluster.edge(tail, head, style="invis", minlen=str(high - low), weight="0")


def _legend(graph: Any, robots: Sequence[str], colours: dict[str, str]) -> None:
    """Robot -> colour boxes, then a bold and a thin sample arrow."""
    with graph.subgraph(name="cluster_legend") as legend:
        legend.attr(label="Legend", style="rounded", color="gray60", fontsize="11")
        legend.node_attr.update(fontsize="9", margin="0.08,0.04", height="0.3")
        for index, robot in enumerate(robots):
            legend.node(f"legend_robot_{index}", dot_text(robot), fillcolor=colours[robot])
        samples = (
            ("global", "global channel", GLOBAL_EDGE),
            ("local", "local channel", LOCAL_EDGE),
        )
        previous = f"legend_robot_{len(robots) - 1}" if robots else ""
        for kind, text, style in samples:
            tail, head = f"legend_{kind}_from", f"legend_{kind}_to"
            with legend.subgraph(name=f"legend_{kind}") as row:
                row.attr(rank="same")
                row.node(tail, "", shape="point", width="0.04", style="invis")
                row.node(head, "", shape="point", width="0.04", style="invis")
            legend.edge(tail, head, text, **style)
            if previous:
                legend.edge(previous, tail, style="invis")
            previous = tail


def configuration_dot(config: Configuration, *, title: str = "", first: Sequence[str] = ()) -> str:
    """DOT source of :func:`configuration_graph`."""
    return str(configuration_graph(config, title=title, first=first).source)
