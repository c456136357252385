"""``relay(D, W, V)``: deep method hierarchies with several alternative
versions per level. A goal needs a datum relayed through D levels; each level
has V versions (a robot of W may relay, locally or via another robot), so
derivations grow as (V*W)**D while the cheapest stays on one robot.
"""

from __future__ import annotations


def relay(depth: int, width: int, versions: int) -> tuple[str, str]:
    """A goal fed through ``depth`` levels of relays with ``versions`` methods each."""
    lines = [
        f";;; Relay chains (benchmarks/families.py): depth {depth}, {width} robots, "
        f"{versions} versions per level.",
        "(make-functionality :name '(sense ?r) :out '((d0 ?r)))",
        f"(make-functionality :name '(act ?r) :in '((d{depth} ?r)))",
    ]
    for level in range(1, depth + 1):
        prev = level - 1
        lines.append(
            f"(make-functionality :name '(relay{level} ?r ?s) :in '((d{prev} ?s)) "
            f":out '((d{level} ?r)))"
        )
        lines.append(
            f"(make-functionality :name '(filter{level} ?r) :in '((d{prev} ?r)) "
            f":out '((d{level} ?r)))"
        )
    lines.append(
        "(make-config-method :name '(get0 ?r) :precond '((robot ?r)) :out '((?a (d0 ?r))) "
        ":body '((?a (sense ?r))))"
    )
    for level in range(1, depth + 1):
        prev = level - 1
        # Version 1: filter locally. Versions 2..V: relay from a helper robot.
        lines.append(
            f"(make-config-method :name '(get{level} ?r) :out '((?b (d{level} ?r))) "
            f":channels '(((local ?r) ?a ?b (d{prev} ?r))) "
            f":body '((?a (get{prev} ?r)) (?b (filter{level} ?r))))"
        )
        for v in range(2, versions + 1):
            lines.append(
                f"(make-config-method :name '(get{level} ?r) "
                f":precond '((robot ?s) (link{v} ?s ?r)) :out '((?b (d{level} ?r))) "
                f":channels '(((global ?s ?r) ?a ?b (d{prev} ?s))) "
                f":body '((?a (get{prev} ?s)) (?b (relay{level} ?r ?s))))"
            )
    lines.append(
        f"(make-config-method :name '(task ?r) :precond '((robot ?r)) "
        f":channels '(((local ?r) ?a ?b (d{depth} ?r))) "
        f":body '((?a (get{depth} ?r)) (?b (act ?r))))"
    )
    facts = [f"(robot R{i})" for i in range(1, width + 1)]
    for v in range(2, versions + 1):
        facts += [
            f"(link{v} R{i} R{j})"
            for i in range(1, width + 1)
            for j in range(1, width + 1)
            if i != j
        ]
    state = "(state " + "\n       ".join(facts) + ")\n(goal (task R1))\n"
    return "\n".join(lines) + "\n", state
