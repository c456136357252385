"""``fusion(M, V, P, H)``: one robot fuses M pieces of information.

Robot F runs ``fuse``, which needs M inputs. Piece m comes from V method
versions; version v processes one or two of P sensor kinds (which ones
follows from m and v) with a processing functionality whose ``:cost`` is 1
to 3, either on F itself (when F carries those sensors) or on any of H
helper robots that carry them, sending the result over a global channel to
a receiver on F. F carries every other sensor kind; helper i carries the
kinds i, i+1 and i+3 (mod P). A helper and its sensors serve every piece
they can, so the cheapest configuration is a small cover of helpers: a
weighted covering problem.
"""

from __future__ import annotations


def _kinds(m: int, v: int, p: int) -> tuple[int, ...]:
    first = (m * 7 + v * 3) % p
    if (m + v) % 2:
        return (first,)
    second = (first + 1 + (m + 2 * v) % (p - 1)) % p if p > 1 else first
    return tuple(sorted({first, second}))


def fusion(m: int, v: int, p: int, h: int) -> tuple[str, str]:
    """Domain and state text: ``m`` pieces, ``v`` versions, ``p`` sensor kinds, ``h`` helpers."""
    if m < 1 or v < 1 or p < 1 or h < 0:
        raise ValueError("need M, V, P >= 1 and H >= 0")
    inputs = " ".join(f"(info{i} ?r)" for i in range(1, m + 1))
    lines = [
        f";;; Fusion (benchmarks/families/fusion.py): M={m} pieces, V={v} versions, "
        f"P={p} sensor kinds, H={h} helpers.",
        f"(make-functionality :name '(fuse ?r) :in '({inputs}))",
    ]
    for k in range(p):
        lines.append(
            f"(make-functionality :name '(sensor{k} ?r) :precond '((has{k} ?r)) "
            f":out '((raw{k} ?r)))"
        )
    for i in range(1, m + 1):
        lines.append(
            f"(make-functionality :name '(receive{i} ?r ?h) :in '((part{i} ?h ?r)) "
            f":out '((info{i} ?r)))"
        )
        for j in range(1, v + 1):
            kinds = _kinds(i, j, p)
            cost = 1 + (i + j) % 3
            raw = " ".join(f"(raw{k} ?h)" for k in kinds)
            lines.append(
                f"(make-functionality :name '(process{i}-{j} ?h ?r) :in '({raw}) "
                f":out '((part{i} ?h ?r)) :cost {cost})"
            )
            has = " ".join(f"(has{k} ?h)" for k in kinds)
            sensors = " ".join(f"(?s{k} (sensor{k} ?h))" for k in kinds)
            wires = " ".join(f"((local ?h) ?s{k} ?q (raw{k} ?h))" for k in kinds)
            # On the fusing robot itself: the part is its information.
            lines.append(
                f"(make-config-method :name '(get{i} ?r) :precond '((robot ?r) (eval 't) "
                f"(fuser ?r) {has.replace('?h', '?r')})\n"
                f"  :out '((?x (info{i} ?r)))\n"
                f"  :channels '({wires.replace('?h', '?r')} ((local ?r) ?q ?x (part{i} ?r ?r)))\n"
                f"  :body '({sensors.replace('?h', '?r')} (?q (process{i}-{j} ?r ?r)) "
                f"(?x (receive{i} ?r ?r))))"
            )
            # On a helper: a global channel to a receiver on the fusing robot.
            lines.append(
                f"(make-config-method :name '(get{i} ?r) :precond '((helper ?h) {has})\n"
                f"  :out '((?x (info{i} ?r)))\n"
                f"  :channels '({wires} ((global ?h ?r) ?q ?x (part{i} ?h ?r)))\n"
                f"  :body '({sensors} (?q (process{i}-{j} ?h ?r)) (?x (receive{i} ?r ?h))))"
            )
    body = " ".join(f"(?g{i} (get{i} ?r))" for i in range(1, m + 1))
    wires = " ".join(f"((local ?r) ?g{i} ?f (info{i} ?r))" for i in range(1, m + 1))
    lines.append(
        f"(make-config-method :name '(do-fuse ?r) :precond '((fuser ?r))\n"
        f"  :channels '({wires})\n  :body '((?f (fuse ?r)) {body}))"
    )
    facts = ["(robot F)", "(fuser F)"] + [f"(has{k} F)" for k in range(0, p, 2)]
    for i in range(1, h + 1):
        facts += [f"(robot H{i})", f"(helper H{i})"]
        facts += [f"(has{k} H{i})" for k in sorted({i % p, (i + 1) % p, (i + 3) % p})]
    state = "(state " + "\n       ".join(facts) + ")\n(goal (do-fuse F))\n"
    return "\n".join(lines) + "\n", state
