"""Shared and recursive sub-derivations: shapes where one ground
method instance occurs under many ancestors.

- ``dag(D)``: D levels; level i either refines level i-1 (one functionality
  of ``:cost`` 3) or fuses levels i-1 and i-2 (one of cost 1, two channels).
  Each level's derivation is used by the next two: expanded the same way at
  both occurrences, the second one adds nothing (its functionalities are
  reused, its channels merged), so fusing everywhere is the optimum — but each
  occurrence may be expanded its own way (4.5), and a search that does not
  see the sharing prices every occurrence again.
- ``conversion(D)``: one generic ``(get ?t)`` derives a data type from any
  type it converts from, over a graph of D+1 types (forward edges i-1 → i,
  inverse edges i+1 → i, skip edges i-2 → i), only the first type sensed.
  The recursion guard of 4.5 prunes a ``get`` only on its own expansion path,
  so each type is derived again under every path of its ancestors.
"""

from __future__ import annotations


def dag(depth: int) -> tuple[str, str]:
    """Domain and state text of a ``depth``-level fusing chain (``depth`` >= 2)."""
    if depth < 2:
        raise ValueError("need D >= 2")
    lines = [
        f";;; Shared sub-derivations (benchmarks/families/shared.py): D={depth} levels.",
        "(make-functionality :name '(sense ?r) :out '((d0 ?r)))",
        f"(make-functionality :name '(act ?r) :in '((d{depth} ?r)))",
        "(make-config-method :name '(level0 ?r) :out '((?s (d0 ?r))) :body '((?s (sense ?r))))",
    ]
    for i in range(1, depth + 1):
        lines += [
            f"(make-functionality :name '(step{i} ?r) :in '((d{i - 1} ?r)) "
            f":out '((d{i} ?r)) :cost 3)",
            f"(make-config-method :name '(level{i} ?r) :out '((?x (d{i} ?r)))\n"
            f"  :channels '(((local ?r) ?a ?x (d{i - 1} ?r)))\n"
            f"  :body '((?a (level{i - 1} ?r)) (?x (step{i} ?r))))",
        ]
        if i >= 2:
            lines += [
                f"(make-functionality :name '(fuse{i} ?r) :in '((d{i - 1} ?r) (d{i - 2} ?r)) "
                f":out '((d{i} ?r)) :cost 1)",
                f"(make-config-method :name '(level{i} ?r) :out '((?x (d{i} ?r)))\n"
                f"  :channels '(((local ?r) ?a ?x (d{i - 1} ?r))\n"
                f"              ((local ?r) ?b ?x (d{i - 2} ?r)))\n"
                f"  :body '((?a (level{i - 1} ?r)) (?b (level{i - 2} ?r)) (?x (fuse{i} ?r))))",
            ]
    lines.append(
        "(make-config-method :name '(task ?r) "
        f":channels '(((local ?r) ?l ?a (d{depth} ?r)))\n"
        f"  :body '((?l (level{depth} ?r)) (?a (act ?r))))"
    )
    return "\n".join(lines) + "\n", "(state (robot R))\n(goal (task R))\n"


def conversion(depth: int) -> tuple[str, str]:
    """Domain and state text of a conversion graph over ``depth`` + 1 types."""
    if depth < 2:
        raise ValueError("need D >= 2")
    edges = {
        "forward": (2, [(i - 1, i) for i in range(1, depth + 1)]),
        "inverse": (1, [(i + 1, i) for i in range(depth)]),  # cheap, but from above
        "skip": (4, [(i - 2, i) for i in range(2, depth + 1)]),  # dear, one step less
    }
    lines = [
        f";;; Recursion over a conversion graph (benchmarks/families/shared.py): D={depth}.",
        "(make-functionality :name '(sense ?r ?t) :precond '((sensor ?r) (sensed ?t))\n"
        "  :out '((data ?t ?r)))",
        f"(make-functionality :name '(act ?r) :in '((data T{depth} ?r)))",
        "(make-config-method :name '(get ?t ?r) :precond '((sensed ?t))\n"
        "  :out '((?s (data ?t ?r))) :body '((?s (sense ?r ?t))))",
    ]
    for kind, (cost, _) in edges.items():
        lines += [
            f"(make-functionality :name '({kind} ?r ?a ?b) :precond '(({kind} ?a ?b))\n"
            f"  :in '((data ?a ?r)) :out '((data ?b ?r)) :cost {cost})",
            f"(make-config-method :name '(get ?t ?r) :precond '(({kind} ?a ?t))\n"
            "  :out '((?x (data ?t ?r))) :channels '(((local ?r) ?g ?x (data ?a ?r)))\n"
            f"  :body '((?g (get ?a ?r)) (?x ({kind} ?r ?a ?t))))",
        ]
    lines.append(
        "(make-config-method :name '(task ?r) "
        f":channels '(((local ?r) ?g ?a (data T{depth} ?r)))\n"
        f"  :body '((?g (get T{depth} ?r)) (?a (act ?r))))"
    )
    facts = ["(robot R)", "(sensor R)", "(sensed T0)"]
    facts += [f"({kind} T{a} T{b})" for kind, (_, pairs) in edges.items() for a, b in pairs]
    state = "(state " + " ".join(facts) + ")\n(goal (task R))\n"
    return "\n".join(lines) + "\n", state
