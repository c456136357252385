"""The site's diagrams — the planner page's (docs/explanation/planner.md: the
graph, the strategies and the ranking in one picture) and the switch
protocol's (docs/explanation/switch-protocol.md: who coordinates, takeover and
fencing) — are laid out from their sources, docs/images/NAME.dot, by the
Graphviz that pygraphviz bundles: the SVG a page shows must be what its source
lays out now, so that an edit of the source without the picture (or the other
way round) fails here.
``CFGPLAN_UPDATE_GOLDEN=1`` rewrites the SVG (look at it before committing)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cfgplan.backends.render import render
from tests.backends.support import UPDATE

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "docs" / "images" / "planner.dot"


def _texts(svg: bytes) -> list[str]:
    """The words the picture shows, in order: the layout's coordinates depend
    on the fonts of the machine, the words do not."""
    return re.findall(r"<text[^>]*>([^<]*)</text>", svg.decode("utf-8"))


@pytest.mark.parametrize(("name", "words"), [("planner", 40), ("takeover", 20)])
def test_a_diagram_is_laid_out_from_its_source(name: str, words: int) -> None:
    source, picture = (ROOT / "docs" / "images" / f"{name}.{kind}" for kind in ("dot", "svg"))
    laid_out = render(source.read_text(encoding="utf-8"), "svg")
    if UPDATE:
        picture.write_bytes(laid_out)
    shown = _texts(picture.read_bytes())
    assert len(shown) > words
    assert shown == _texts(laid_out)


def test_the_planner_diagram_names_modules_that_exist() -> None:
    """Every ``name.py`` the diagram names is a module of cfgplan/planner/."""
    lines = SOURCE.read_text(encoding="utf-8").splitlines()
    labels = " ".join(line for line in lines if not line.lstrip().startswith("//"))
    named = set(re.findall(r"\b([a-z_]+)\.py\b", labels.replace("\\n", " ")))
    assert named, "the diagram names no module"
    missing = {m for m in named if not (ROOT / "cfgplan" / "planner" / f"{m}.py").exists()}
    assert not missing
