"""The running configuration's drawing for the live page, its parts tagged.

The drawing is the one ``cfgplan render`` makes (:mod:`cfgplan.backends.dot`,
Fig. 4.3), laid out on the server by :func:`cfgplan.backends.render.render`:
pygraphviz, a dependency of cfgplan whose wheels bundle Graphviz, so neither
a ``dot`` program nor a script in the browser is needed. Laying out takes a
few milliseconds and is done once per configuration, on the server's thread.

Graphviz names each SVG group after its node, edge or cluster (``<title>``).
:func:`tagged` adds what the page needs to colour them without a second
layout: ``data-input`` on each channel (the input it feeds,
:func:`~cfgplan.live.model.input_key`), ``data-resource`` and ``data-robot``
on each functionality, ``data-robot`` on each robot's cluster and legend box.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from cfgplan.backends.dot import channel_label, configuration_dot, robot_order
from cfgplan.configuration.model import Channel, Configuration
from cfgplan.diagnostics import CfgplanError
from cfgplan.live.model import input_key
from cfgplan.notation import call_text

__all__ = ["drawing", "tagged"]

SVG = "http://www.w3.org/2000/svg"
XLINK = "http://www.w3.org/1999/xlink"
_CLUSTER = re.compile(r"cluster_(\d+)_")
_LEGEND = re.compile(r"legend_robot_(\d+)$")


def drawing(config: Configuration, first: Sequence[str] = ()) -> tuple[str, str | None]:
    """The DOT source of ``config`` and its tagged SVG (``None``: no Graphviz
    layout engine here; the page then shows the DOT source)."""
    source = configuration_dot(config, first=first)
    from cfgplan.backends.render import render

    try:
        svg = render(source, "svg").decode("utf-8")
    except CfgplanError:
        return source, None
    return source, tagged(svg, config, first)


def _texts(group: ET.Element) -> list[str]:
    return [t.text or "" for t in group.iter(f"{{{SVG}}}text")]


def _title(group: ET.Element) -> str:
    found = group.find(f"{{{SVG}}}title")
    return "" if found is None or found.text is None else found.text


def tagged(svg: str, config: Configuration, first: Sequence[str] = ()) -> str:
    """Graphviz's SVG of ``config`` with its parts tagged (module docstring)."""
    ET.register_namespace("", SVG)
    ET.register_namespace("xlink", XLINK)
    root = ET.fromstring(svg)
    robots = robot_order(config, first)
    boxes = {f.label: f for f in config.functionalities}
    wires: dict[tuple[str, str, str], Channel] = {}
    for each in config.channels:
        wires[(each.source, each.target, channel_label(each).split("\\n")[0])] = each
    for group in root.iter(f"{{{SVG}}}g"):
        kind, title = group.get("class"), _title(group)
        if kind == "node" and title in boxes:
            f = boxes[title]
            group.set("data-resource", call_text(f.key))
            group.set("data-robot", f.robot)
        elif kind == "node" and (legend := _LEGEND.match(title)) is not None:
            index = int(legend.group(1))
            if index < len(robots):
                group.set("data-robot", robots[index])
        elif kind == "cluster" and (cluster := _CLUSTER.match(title)) is not None:
            index = int(cluster.group(1))
            if index < len(robots):
                group.set("data-robot", robots[index])
        elif kind == "edge":
            source, _, target = title.partition("->")
            texts = _texts(group)
            ch = wires.get((source, target, texts[0])) if texts else None
            if ch is not None:
                group.set("data-input", input_key(ch.target, ch.data))
                group.set("data-kind", ch.kind)
    root.set("width", "100%")
    root.attrib.pop("height", None)
    return ET.tostring(root, encoding="unicode")
