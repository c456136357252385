"""``chain(D)``: a deep hierarchy, D levels of methods with 3 versions each.

Level i turns the datum of level i+1 into its own: version 1 with one
functionality of ``:cost`` 3, version 2 with two of cost 1 each, version 3
with one of cost 1 on the helper robot H (sent back over a global channel
to a receiver). Versions 1 and 2 cost the same (4 with their channels), the
helper costs 10 once and then 5 a level: long plateaus of equal cost.
"""

from __future__ import annotations


def chain(depth: int) -> tuple[str, str]:
    """Domain and state text of a ``depth``-level chain."""
    if depth < 1:
        raise ValueError("need D >= 1")
    lines = [
        f";;; Deep chain (benchmarks/families/chain.py): D={depth} levels.",
        f"(make-functionality :name '(sense ?r) :out '((d{depth} ?r)))",
        "(make-functionality :name '(act ?r) :in '((d0 ?r)))",
    ]
    for i in range(depth):
        n = i + 1
        lines += [
            f"(make-functionality :name '(heavy{i} ?r) :in '((d{n} ?r)) :out '((d{i} ?r)) :cost 3)",
            f"(make-functionality :name '(pre{i} ?r) :in '((d{n} ?r)) :out '((e{i} ?r)) :cost 1)",
            f"(make-functionality :name '(post{i} ?r) :in '((e{i} ?r)) :out '((d{i} ?r)) :cost 1)",
            f"(make-functionality :name '(remote{i} ?h ?r) :in '((d{n} ?r)) "
            f":out '((h{i} ?h ?r)) :cost 1)",
            f"(make-functionality :name '(back{i} ?r ?h) :in '((h{i} ?h ?r)) :out '((d{i} ?r)))",
        ]
        below = f"(?b (level{n} ?r))" if n < depth else "(?b (sense ?r))"
        lines += [
            f"(make-config-method :name '(level{i} ?r) :out '((?x (d{i} ?r)))\n"
            f"  :channels '(((local ?r) ?b ?x (d{n} ?r)))\n"
            f"  :body '({below} (?x (heavy{i} ?r))))",
            f"(make-config-method :name '(level{i} ?r) :out '((?y (d{i} ?r)))\n"
            f"  :channels '(((local ?r) ?b ?x (d{n} ?r)) ((local ?r) ?x ?y (e{i} ?r)))\n"
            f"  :body '({below} (?x (pre{i} ?r)) (?y (post{i} ?r))))",
            f"(make-config-method :name '(level{i} ?r) :precond '((helper ?h))\n"
            f"  :out '((?y (d{i} ?r)))\n"
            f"  :channels '(((global ?r ?h) ?b ?x (d{n} ?r)) ((global ?h ?r) ?x ?y (h{i} ?h ?r)))\n"
            f"  :body '({below} (?x (remote{i} ?h ?r)) (?y (back{i} ?r ?h))))",
        ]
    lines.append(
        "(make-config-method :name '(task ?r) :channels '(((local ?r) ?l ?a (d0 ?r)))\n"
        "  :body '((?l (level0 ?r)) (?a (act ?r))))"
    )
    state = "(state (robot R) (robot H) (helper H))\n(goal (task R))\n"
    return "\n".join(lines) + "\n", state
