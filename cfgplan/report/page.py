"""``report.html``: one self-contained page of a run's report.

Every picture is inline SVG (matplotlib's, with its text as paths, and
Graphviz's), the style sheet is in the page, nothing is loaded from
anywhere: the file opens offline, mailed or archived alone. Each SVG's ids
are prefixed with its own name (``timeline-…``), so that pictures drawn apart
cannot take each other's clip paths or glyphs. The page holds the outcome,
the timeline, the table of switches, failures and recoveries, each
configuration's diagram, and, for a simulation, the trajectories and the
bar's length.
"""

from __future__ import annotations

import html
import re
from dataclasses import dataclass

from cfgplan.report.story import Story, cost_text, role

__all__ = ["Figure", "inline_svg", "page"]

STYLE = """
body { font: 15px/1.45 system-ui, sans-serif; margin: 2em auto; max-width: 1150px;
       padding: 0 1em; color: #222; }
h1 { font-size: 1.5em; margin-bottom: .2em; } h2 { margin-top: 1.8em; font-size: 1.2em; }
figure { margin: 1em 0; } figure svg { max-width: 100%; height: auto; display: block; }
figcaption { color: #555; font-size: .9em; }
table { border-collapse: collapse; font-size: .92em; }
td, th { border-bottom: 1px solid #ddd; padding: .25em .7em; text-align: left;
         vertical-align: top; }
td:first-child { white-space: nowrap; }
tr.switch td:first-child { border-left: 4px solid #333; }
tr.failure td:first-child { border-left: 4px solid #d62728; }
tr.recovery td:first-child { border-left: 4px solid #2e8b57; }
tr.no-configuration td:first-child { border-left: 4px solid #7b3294; }
.note { color: #8a5a00; }
"""


@dataclass(frozen=True)
class Figure:
    """A picture of the page: its anchor, heading, SVG text and caption."""

    name: str
    heading: str
    svg: str
    caption: str = ""


_XML_HEAD = re.compile(r"^\s*(<\?xml[^>]*\?>\s*)?(<!DOCTYPE[^>]*>\s*)?(<!--.*?-->\s*)*", re.S)
_METADATA = re.compile(r"<metadata>.*?</metadata>\s*", re.S)
_ID = re.compile(r'\bid="([^"]+)"')


def inline_svg(svg: str, prefix: str) -> str:
    """``svg`` without its XML prologue and metadata, every id (and reference to it) prefixed."""
    body = _METADATA.sub("", _XML_HEAD.sub("", svg, count=1))
    ids = set(_ID.findall(body))
    if not ids:
        return body

    def rename(found: re.Match[str]) -> str:
        name = found.group(2)
        return f"{found.group(1)}{prefix}-{name}" if name in ids else found.group(0)

    body = _ID.sub(lambda m: f'id="{prefix}-{m.group(1)}"', body)
    return re.sub(r'(url\(#|href="#)([^")]+)', rename, body)


def _events(story: Story) -> str:
    from cfgplan.sim.record import detail as detail_text  # without the file and line

    rows = []
    for m in story.of("switch", "no-configuration", "failure", "recovery", "change", "drop"):
        detail = ""
        if m.what == "failure":
            how = m.record.get("how", "")
            seen = m.record.get("detected_by", "")
            said = detail_text(str(m.record.get("detail") or ""))
            detail = f"{how}, seen by {seen}" + (f": {said}" if said else "")
        elif m.what == "recovery":
            detail = f"{m.record.get('how', '')}, seen by {m.record.get('detected_by', '')}"
        elif m.what == "switch":
            detail = f"from the {m.record.get('source', '')}"
        elif m.what == "no-configuration":
            detail = "; ".join(str(w) for w in m.record.get("why") or [])[:400]
        rows.append(
            f'<tr class="{html.escape(m.what)}" data-t="{m.t:g}"><td>{m.t:.2f} s</td>'
            f"<td>{html.escape(m.what)}</td><td>{html.escape(m.robot)}</td>"
            f"<td>{html.escape(m.text)}</td><td>{html.escape(detail)}</td></tr>"
        )
    if not rows:
        return "<p>No switch, failure or recovery: the first configuration ran throughout.</p>"
    head = "<tr><th>time</th><th>what</th><th>robot</th><th></th><th>detail</th></tr>"
    return f'<table id="events">{head}{"".join(rows)}</table>'


def _configurations(story: Story) -> str:
    rows = []
    for number, span in sorted(story.configurations().items()):
        roles = "; ".join(f"{r}: {role(span.config, r)}" for r in span.config.agents)
        times = ", ".join(f"{s.start:g}–{s.end:g} s" for s in story.spans if s.number == number)
        rows.append(
            f'<tr><td><a href="#configuration-{number}">#{number}</a></td>'
            f"<td>{cost_text(span.config)}</td><td>{html.escape(span.goal)}</td>"
            f"<td>{html.escape(times)}</td><td>{html.escape(roles)}</td></tr>"
        )
    head = "<tr><th>#</th><th>cost</th><th>goal</th><th>ran</th><th>robots</th></tr>"
    return f'<table id="configurations">{head}{"".join(rows)}</table>'


def page(story: Story, figures: list[Figure], facts: list[str], notes: list[str]) -> str:
    """The whole page (module docstring)."""
    title = html.escape(story.title or "A run")
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{title}: report</title><style>{STYLE}</style></head><body>",
        f"<h1>{title}</h1>",
        '<ul id="facts">' + "".join(f"<li>{html.escape(f)}</li>" for f in facts) + "</ul>",
    ]
    parts += [f'<p class="note">{html.escape(n)}</p>' for n in notes]
    parts.append("<h2>Switches, failures and recoveries</h2>" + _events(story))
    parts.append("<h2>Configurations</h2>" + _configurations(story))
    for fig in figures:
        caption = f"<figcaption>{html.escape(fig.caption)}</figcaption>" if fig.caption else ""
        parts.append(
            f'<section id="{html.escape(fig.name)}"><h2>{html.escape(fig.heading)}</h2>'
            f"<figure>{inline_svg(fig.svg, fig.name)}{caption}</figure></section>"
        )
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
