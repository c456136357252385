"""The one notation of atoms, calls and s-expressions (:mod:`cfgplan.notation`):
s-expressions as the domain language writes them (4.4), instances and data
as the configuration descriptions print them (4.6)."""

from __future__ import annotations

from cfgplan.configuration.model import FunctionalityInstance
from cfgplan.ir.model import Atom, Eval, Negation
from cfgplan.notation import atom_text, call_text, instance_text, sexpr_text
from cfgplan.runtime.transport import ChannelKey
from cfgplan.syntax.printer import format_condition, format_sexpr


def test_atoms_and_calls() -> None:
    assert atom_text(("in", "Pippi", "Room1")) == "(in Pippi Room1)"
    assert call_text(("get-door-info", "Pippi", "Door1")) == "get-door-info(Pippi, Door1)"
    assert call_text(("go",)) == "go()"
    assert instance_text("F3", "cross-door", ("Pippi", "Door1")) == "F3: cross-door(Pippi, Door1)"


def test_the_models_print_through_it() -> None:
    """The IR, configurations and the runtime's channel keys say the same."""
    atom = Atom(predicate="in", args=("Pippi", "Room1"))
    assert str(atom) == format_condition(atom) == "(in Pippi Room1)"
    assert str(Negation(atom=atom)) == "(not (in Pippi Room1))"
    test = Eval(expr=["not", ["eql", ["quote", "?r"], ["quote", "?rh1"]]])
    assert str(test) == format_condition(test) == "(eval (not (eql (quote ?r) (quote ?rh1))))"
    f = FunctionalityInstance(label="F8", name="camera", args=("Emil",))
    assert str(f) == "F8: camera(Emil)"
    key = ChannelKey("F7", "F3", ("pos", "Pippi", "Door1"))
    assert str(key) == "F7->F3 (pos Pippi Door1)"


def test_sexpr_leaves_and_depth() -> None:
    """Leaves are written by ``leaf``; nesting deeper than the stack allows is
    written all the same (no recursion)."""
    assert sexpr_text(["+", 1, 2.5, ["quote", "a"]]) == "(+ 1 2.5 (quote a))"
    assert sexpr_text(["<", "?b", 20], lambda x: str(x).upper()) == "(< ?B 20)"
    assert format_sexpr(["=", 1e-05, 2]) == "(= 0.00001 2)"  # reads back as a float
    deep: list[object] = []
    inner = deep
    for _ in range(50_000):
        inner.append([])
        inner = inner[0]  # type: ignore[assignment]
    text = sexpr_text(deep)
    assert text == "(" * 50_001 + ")" * 50_001
