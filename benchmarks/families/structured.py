"""``structured(seed, ...)``: randomised domains of the structures that made
the search fall off cliffs, for sweeps over their parameters
(``python -m benchmarks.sweeps --only structured``).

One goal robot G fuses ``pieces`` pieces of information. Piece i has
``versions`` method versions; each needs one or two of ``kinds`` sensor
kinds, read through a *filter* of that kind on the robot that carries the
sensor: on G itself, or on a helper, the processed piece going to a receiver
on G over a channel declared global (with a bandwidth, where the state
declares media; one from G to G costs as global but needs no medium). The
filters are methods shared by every piece and version that reads that kind
on that robot (siblings share children and reuse filters); a filter is a
chain of ``depth`` refinement levels, each in two versions (on the robot,
or a cheaper one that needs a second sensor kind), so that hierarchies are
deep and shared. There are ``robots`` robots besides G; G and each of them
carry each kind with probability ``density``; ``:cost`` of processing and of some
sensors is 1 to 5. With ``media``, every helper has a medium to G whose
capacity carries about two pieces: the cheapest cover may not fit.

Everything is drawn from ``random.Random(seed)``: the same arguments give
the same text, byte for byte.
"""

from __future__ import annotations

import random


def structured(
    seed: int,
    pieces: int = 12,
    versions: int = 3,
    kinds: int = 6,
    robots: int = 6,
    depth: int = 2,
    density: float = 0.4,
    media: bool = False,
) -> tuple[str, str]:
    """Domain and state text; see the module docstring."""
    if min(pieces, versions, kinds, robots, depth) < 1 or not 0 < density <= 1:
        raise ValueError("need pieces, versions, kinds, robots, depth >= 1 and 0 < density <= 1")
    rng = random.Random(seed)
    lines = [
        f";;; Structured (benchmarks/families/structured.py): seed={seed} pieces={pieces} "
        f"versions={versions} kinds={kinds} robots={robots} depth={depth} "
        f"density={density:g} media={media}.",
        "(make-functionality :name '(fuse ?r) :in '("
        + " ".join(f"(info{i} ?r)" for i in range(1, pieces + 1))
        + "))",
    ]
    for k in range(kinds):
        cost = f" :cost {rng.randint(1, 5)}" if rng.random() < 0.5 else ""
        lines.append(
            f"(make-functionality :name '(sensor{k} ?h) :precond '((has{k} ?h)) "
            f":out '((raw{k} ?h)){cost})"
        )
        # The filter chain of kind k: level 0 reads the sensor; level l refines
        # level l-1 on the robot, or more cheaply with a second kind's sensor.
        other = (k + 1 + rng.randrange(kinds - 1)) % kinds if kinds > 1 else k
        for level in range(depth):
            below = f"(raw{k} ?h)" if level == 0 else f"(f{k}-{level - 1} ?h)"
            call = f"(sensor{k} ?h)" if level == 0 else f"(filter{k}-{level - 1} ?h)"
            lines += [
                f"(make-functionality :name '(smooth{k}-{level} ?h) :in '({below}) "
                f":out '((f{k}-{level} ?h)) :cost {rng.randint(2, 5)})",
                f"(make-functionality :name '(fuse{k}-{level} ?h) :in '({below} (raw{other} ?h)) "
                f":out '((f{k}-{level} ?h)) :cost 1)",
                f"(make-config-method :name '(filter{k}-{level} ?h)\n"
                f"  :out '((?s (f{k}-{level} ?h)))\n"
                f"  :channels '(((local ?h) ?b ?s {below}))\n"
                f"  :body '((?b {call}) (?s (smooth{k}-{level} ?h))))",
                f"(make-config-method :name '(filter{k}-{level} ?h) :precond '((has{other} ?h))\n"
                f"  :out '((?s (f{k}-{level} ?h)))\n"
                f"  :channels '(((local ?h) ?b ?s {below}) ((local ?h) ?o ?s (raw{other} ?h)))\n"
                f"  :body '((?b {call}) (?o (sensor{other} ?h)) (?s (fuse{k}-{level} ?h))))",
            ]
    top = depth - 1
    for i in range(1, pieces + 1):
        lines.append(
            f"(make-functionality :name '(receive{i} ?r ?h) :in '((part{i} ?h ?r)) "
            f":out '((info{i} ?r)))"
        )
        for v in range(1, versions + 1):
            used = sorted(rng.sample(range(kinds), min(kinds, rng.choice((1, 2)))))
            ins = " ".join(f"(f{k}-{top} ?h)" for k in used)
            lines.append(
                f"(make-functionality :name '(process{i}-{v} ?h ?r) :in '({ins}) "
                f":out '((part{i} ?h ?r)) :cost {rng.randint(1, 5)})"
            )
            has = " ".join(f"(has{k} ?h)" for k in used)
            body = " ".join(f"(?g{k} (filter{k}-{top} ?h))" for k in used)
            wires = " ".join(f"((local ?h) ?g{k} ?q (f{k}-{top} ?h))" for k in used)
            bandwidth = f" {rng.choice((2, 3, 4))}" if media else ""
            lines.append(
                f"(make-config-method :name '(get{i} ?r) :precond '((robot ?h) {has})\n"
                f"  :out '((?x (info{i} ?r)))\n"
                f"  :channels '({wires} ((global ?h ?r) ?q ?x (part{i} ?h ?r){bandwidth}))\n"
                f"  :body '({body} (?q (process{i}-{v} ?h ?r)) (?x (receive{i} ?r ?h))))"
            )
    gets = " ".join(f"(?g{i} (get{i} ?r))" for i in range(1, pieces + 1))
    wires = " ".join(f"((local ?r) ?g{i} ?f (info{i} ?r))" for i in range(1, pieces + 1))
    lines.append(
        f"(make-config-method :name '(do-fuse ?r) :precond '((fuser ?r))\n"
        f"  :channels '({wires})\n  :body '((?f (fuse ?r)) {gets}))"
    )
    names = ["G"] + [f"H{j}" for j in range(1, robots + 1)]
    facts = ["(robot G)", "(fuser G)"]
    for name in names:
        if name != "G":
            facts.append(f"(robot {name})")
        carried = [k for k in range(kinds) if rng.random() < density]
        facts += [f"(has{k} {name})" for k in carried]
    if media:
        for name in names[1:]:
            facts.append(f"(medium wifi {name} G {rng.choice((5, 6, 8))})")
    state = "(state " + "\n       ".join(facts) + ")\n(goal (do-fuse G))\n"
    return "\n".join(lines) + "\n", state
