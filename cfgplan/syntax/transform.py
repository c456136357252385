"""The transformer inside the parser (:mod:`cfgplan.syntax.reader`): each
grammar rule of ``grammar/cfgplan.lark`` straight to an :class:`Sx` node or
an IR object, as Lark reduces it, its span from the positions of its first
and last tokens (:class:`ToIR`).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, TypeVar

from lark import Lark, Token
from lark.visitors import Transformer

from cfgplan.diagnostics import CfgplanError, error
from cfgplan.ir.model import Functionality, Goal, Method, Span, State
from cfgplan.syntax import forms
from cfgplan.syntax.sx import Place, Sx, SxKind, token_end

T = TypeVar("T")

MAX_NESTING = 64
"""Lists may nest this deep; deeper input is refused (no recursion anywhere)."""


ATOM_TERMINALS = ("NUMBER", "SYMBOL")
"""What an atom of an ``ATOMS`` token is read as: the terminals of the
grammar's lists of atoms (the token itself matches each as a ``SYMBOL``,
whose text covers a ``NUMBER``'s)."""


def atom_scanner(parser: Lark) -> re.Pattern[str]:
    """What finds the atoms of an ``ATOMS`` token as Lark's lexer would find
    them read one by one: the grammar's own :data:`ATOM_TERMINALS`, each a
    group named after it, tried in the order Lark's lexer tries them (the
    higher priority first: a ``NUMBER`` before a ``SYMBOL``)."""
    terminals = sorted(
        (parser.get_terminal(name) for name in ATOM_TERMINALS),
        key=lambda t: (-t.priority, -t.pattern.max_width, -len(t.pattern.value), t.name),
    )
    return re.compile("|".join(f"(?P<{t.name}>{t.pattern.to_regexp()})" for t in terminals))


class GoalSequence(NamedTuple):
    """``(sequence G1 G2 ...)`` as read; it becomes :attr:`State.sequence` (a
    named tuple: a frozen dataclass takes four times as long to define)."""

    goals: tuple[Goal, ...]
    span: Span


class Run:
    """The children of an inlined rule, passed up to the rule that splices them in."""

    __slots__ = ("children",)

    def __init__(self, children: list[Any]) -> None:
        self.children = children


class ToIR(Transformer[Token, Any]):
    """Maps grammar rules to Sx nodes (generic s-expressions) and IR objects.

    It runs inside the LALR parser (each rule as it is reduced: no parse tree
    is built, nothing recurses), so it takes no ``meta``: a form's or a list's
    span runs from its first token to its last, the parentheses the grammar
    keeps (``LPAR``, ``RPAR``). Lark calls every method named like a rule,
    an inlined ``_rule`` too: the helpers' names are none of the grammar's
    (:meth:`begin`, not ``start``, readies it for each file).

    A form or list found wrong is noted (:attr:`failed`, the first one) and the
    parse goes on: a syntax error anywhere in the file is reported before it,
    as when the whole tree was read first."""

    filename = "<text>"
    failed: tuple[CfgplanError, ...] = ()
    """Every form found wrong, in file order (the others are read all the same)."""
    unread: tuple[str, ...] = ()
    deep = False
    """A list of the form being read nests too deep (said once, not again by the form)."""
    """The names those of them declare, where their :name reads (:func:`forms.declared`)."""
    atoms: re.Pattern[str] | None = None
    """What finds the atoms of an ``ATOMS`` token (:meth:`use`)."""

    def __default__(self, data: str, children: list[Any], meta: Any) -> Run:
        """Every rule without a method of its own: ``start`` and the inlined
        ones (``_expr``, ``_quoted``, ``_form`` and the repetitions
        Lark makes of ``(...)*``), whose children the rule above splices
        into its own (Lark reads only their ``children``).

        Lark's default builds a ``Tree`` and, positions on, works out its
        start and end from its children's (two searches a rule); a
        :class:`Run` carries the children alone. Safe: no span is taken
        from these nodes (spans come from the tokens, :meth:`_span`), and
        what the rule above receives, the children, is the same list."""
        return Run(children)

    def _expr(self, children: list[Any]) -> Run:
        """As :meth:`__default__`, called straight (Lark calls a method named
        like the rule, not through ``__default__``): the inlined rules reduced
        most often (a form's and a call's items; a list names its items'
        rules itself, grammar/cfgplan.lark)."""
        return Run(children)

    _quoted = _form = _expr

    def use(self, parser: Lark) -> None:
        """Read ``ATOMS`` tokens with the terminals of ``parser``, the parser
        this transformer runs in or whose trees it transforms (:func:`atom_scanner`)."""
        self.atoms = atom_scanner(parser)

    def begin(self, filename: str) -> None:
        self.filename, self.failed, self.unread, self.deep = filename, (), (), False

    def _build(self, build: Callable[[], T], children: Sequence[Any] = ()) -> T | None:
        """``build()``, or None when it finds the form wrong (noted, with the
        name the form's ``children`` declare)."""
        deep, self.deep = self.deep, False
        try:
            return build()
        except CfgplanError as exc:
            if not deep:  # a list nested too deep inside said it (its items are gone)
                self.failed += (exc,)
            name = forms.declared(children)
            if name is not None:
                self.unread += (name,)
            return None

    def _span(self, first: Token, last: Token | Sx) -> Span:
        """From the start of the token ``first`` to the end of ``last``. The
        Span is made from the two positions directly (before, from a Span made
        for each token, two pydantic models thrown away a list): the same
        numbers, the same Span."""
        end_line, end_column = last.end if isinstance(last, Sx) else token_end(last)
        return Span(
            file=self.filename,
            line=first.line or 0,
            column=first.column or 0,
            end_line=end_line,
            end_column=end_column,
        )

    def _leaf(self, child: Any) -> Any:
        """A ``SYMBOL`` or ``NUMBER`` token as its node, anything else as it
        is. Symbols and numbers have no rule of their own (one reduction
        fewer each: chain D=100's domain is read in 3 % fewer instructions),
        so a rule that holds one makes it a node here."""
        if type(child) is Token:
            kind = child.type
            if kind == "SYMBOL":
                return Sx("symbol", text=str(child), at=child, file=self.filename)
            if kind == "NUMBER":
                return Sx("number", text=str(child), at=child, file=self.filename)
            if kind == "ATOMS":
                return self._atoms(child)
        return child

    def _atoms(self, tok: Token) -> Sx:
        """An ``ATOMS`` token, a list of atoms on one line, as the node
        :meth:`list` makes of the same text read token by token: each atom a
        symbol or number node placed where it stands (a :class:`Place`, no
        token made), the list's span the token's."""
        if self.atoms is None:
            raise RuntimeError("ToIR.use(parser) tells the transformer its parser's terminals")
        filename, line, column = self.filename, tok.line or 0, tok.column or 0
        items = []
        for found in self.atoms.finditer(tok):
            start, end = found.span()
            at = Place(line, column + start, line, column + end)
            kind: SxKind = "number" if found.lastgroup == "NUMBER" else "symbol"
            items.append(Sx(kind, text=found.group(), at=at, file=filename))
        return Sx("list", self._span(tok, tok), items=tuple(items), depth=1)  # atoms only

    def list(self, children: Sequence[Any]) -> Sx:
        item = self._leaf
        span = self._span(children[0], children[-1])
        return self._list(span, [item(c) for c in children[1:-1]])

    def _list(self, span: Span, items: Sequence[Any]) -> Sx:
        depth = 1 + max((i.depth for i in items), default=0)
        if depth > MAX_NESTING:
            self.deep = True
            if depth == MAX_NESTING + 1:  # said once, where the nesting first goes too deep
                self.failed += (
                    error(
                        f"lists nest more than {MAX_NESTING} levels deep here",
                        span,
                        "domains and states need only a few levels; check for a runaway '('",
                    ),
                )
            items = ()  # nothing deeper is kept: no check ever walks it
        return Sx("list", span, items=tuple(items), depth=depth)

    def quote(self, children: Sequence[Any]) -> Sx:
        quote_tok, value = children[0], self._leaf(children[1])
        head = Sx("symbol", text="quote", at=quote_tok, file=self.filename)
        return self._list(self._span(quote_tok, value), [head, value])

    def call(self, children: Sequence[Any]) -> Sx:
        name_tok, *args, _ = children
        head = Sx("symbol", text=str(name_tok), at=name_tok, file=self.filename)
        span = self._span(name_tok, children[-1])
        return self._list(span, [head, *(self._leaf(a) for a in args if a is not None)])

    def option(self, children: Sequence[Any]) -> forms.Option:
        keyword, *rest = children
        value = self._leaf(rest[-1])
        text = str(keyword)
        return forms.Option(text, Sx("symbol", text=text, at=keyword, file=self.filename), value)

    def functionality(self, children: Sequence[Any]) -> Functionality | None:
        span = self._span(children[0], children[-1])
        return self._build(lambda: forms.functionality(span, children[2:-1]), children[2:-1])

    def method(self, children: Sequence[Any]) -> Method | None:
        span = self._span(children[0], children[-1])
        return self._build(lambda: forms.method(span, children[2:-1]), children[2:-1])

    def state(self, children: Sequence[Any]) -> State | None:
        span = self._span(children[0], children[-1])
        items = [self._leaf(c) for c in children[2:-1]]
        return self._build(lambda: forms.state(span, items))

    def goal(self, children: Sequence[Any]) -> Goal | None:
        value = next(c for c in map(self._leaf, children[2:-1]) if isinstance(c, Sx))
        span = self._span(children[0], children[-1])
        return self._build(lambda: forms.goal(span, value))

    def sequence(self, children: Sequence[Any]) -> GoalSequence | None:
        span = self._span(children[0], children[-1])
        goals = [c for c in map(self._leaf, children[2:-1]) if isinstance(c, Sx)]
        return self._build(lambda: GoalSequence(tuple(forms.goal(c.span, c) for c in goals), span))
