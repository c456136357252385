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


MISSIONS = """\
;;; Missions (benchmarks/families/steps.py): {g} goal robots, {h} helpers{moving}.
(make-functionality :name '(sense ?h ?k) :precond '((helper ?h)) :out '((data ?h ?k)))
(make-functionality :name '(recv ?r ?h ?k) :in '((data ?h ?k)) :out '((got ?r ?k)))
(make-functionality :name '(fuse ?r ?a ?b) :precond '((at ?r ?a))
  :in '((got ?r k1) (got ?r k2) (got ?r k3)){post})
(make-config-method :name '(get ?r ?k) :precond '((helper ?h))
  :out '((?b (got ?r ?k)))
  :channels '(((global ?h ?r) ?a ?b (data ?h ?k)))
  :body '((?a (sense ?h ?k)) (?b (recv ?r ?h ?k))))
(make-config-method :name '(mission ?r ?b) :precond '((at ?r ?a))
  :channels '(((local ?r) ?x ?f (got ?r k1)) ((local ?r) ?y ?f (got ?r k2))
              ((local ?r) ?z ?f (got ?r k3)))
  :body '((?x (get ?r k1)) (?y (get ?r k2)) (?z (get ?r k3)) (?f (fuse ?r ?a ?b))))
"""


def missions(
    goals: int, helpers: int, moving: bool = False, patrol: bool = False
) -> tuple[str, str]:
    """Domain and state text: a sequence of ``goals`` missions, one for each
    goal robot G1..G``goals``, each needing three kinds of data that any of
    ``helpers`` helpers can send (the shape of a sequence that enumerated its
    steps: independent goals). With ``moving``, each mission moves its robot
    to the next place (a postcondition (at G P)): the later steps read where
    the other robots are not, so the steps stay independent. With ``patrol``
    (which implies ``moving``), one robot G1 does every mission, from place to
    place: each step reads where the step before left it (every helper's
    configuration moves it alike)."""
    if goals < 1 or helpers < 1:
        raise ValueError("need G >= 1 goals and H >= 1 helpers")
    moving = moving or patrol
    post = "\n  :postcond '((not (at ?r ?a)) (at ?r ?b))" if moving else ""
    robots = [1] * goals if patrol else list(range(1, goals + 1))
    facts = ["(place Dock)"] + [f"(place Place{i})" for i in range(1, goals + 1)]
    facts += [f"(robot G{i}) (at G{i} Dock)" for i in sorted(set(robots))]
    facts += [f"(robot H{i}) (helper H{i})" for i in range(1, helpers + 1)]
    steps = " ".join(f"(mission G{r} Place{i})" for i, r in enumerate(robots, 1))
    state = "(state " + "\n       ".join(facts) + f")\n(sequence {steps})\n"
    how = ", one robot moving from place to place" if patrol else ", each moving its robot"
    text = MISSIONS.format(g=goals, h=helpers, moving=how if moving else "", post=post)
    return text, state
