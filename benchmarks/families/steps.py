"""``deliveries(S, R)``: a sequence of S steps for R robots.

Step i delivers parcel Pi: some robot carries it, sensing its way with its
own sonar (cheap) — which wears it: it is ``(fresh ?r)`` no more — or, once
worn, with a laser too (one more functionality). Each step can go to any of
the R robots, so the states the steps leave are the sets of worn robots:
the sequence search merges the states it meets again, and the cheapest
sequence spreads the work (cheapest step after cheapest step would not).
"""

from __future__ import annotations

DOMAIN = """\
;;; Deliveries (benchmarks/families/steps.py): {s} parcels, {r} robots.
(make-functionality :name '(sonar ?r) :out '((range ?r)))
(make-functionality :name '(laser ?r) :out '((scan ?r)))
(make-functionality :name '(carry ?r ?p) :precond '((fresh ?r))
  :in '((range ?r)) :postcond '((not (fresh ?r)) (delivered ?p)))
(make-functionality :name '(carry-worn ?r ?p) :precond '((robot ?r))
  :in '((range ?r) (scan ?r)) :postcond '((delivered ?p)))
(make-config-method :name '(deliver ?p) :precond '((parcel ?p) (robot ?r) (fresh ?r))
  :channels '(((local ?r) ?s ?c (range ?r)))
  :body '((?s (sonar ?r)) (?c (carry ?r ?p))))
(make-config-method :name '(deliver ?p) :precond '((parcel ?p) (robot ?r))
  :channels '(((local ?r) ?s ?c (range ?r)) ((local ?r) ?l ?c (scan ?r)))
  :body '((?s (sonar ?r)) (?l (laser ?r)) (?c (carry-worn ?r ?p))))
"""


def deliveries(steps: int, robots: int) -> tuple[str, str]:
    """Domain and state text: ``steps`` parcels delivered in order by ``robots`` robots."""
    if steps < 1 or robots < 1:
        raise ValueError("need S >= 1 steps and R >= 1 robots")
    facts = [f"(robot R{i}) (fresh R{i})" for i in range(1, robots + 1)]
    facts += [f"(parcel P{i})" for i in range(1, steps + 1)]
    goals = " ".join(f"(deliver P{i})" for i in range(1, steps + 1))
    state = "(state " + "\n       ".join(facts) + f")\n(sequence {goals})\n"
    return DOMAIN.format(s=steps, r=robots), state
