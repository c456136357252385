"""Structures the search is still weak on (docs/explanation/planner.md, "Weak spots"), found by a
helper writing domains to defeat it; each generator returns the text of a
domain and of a state with its goal:

- ``overlap(M, H)``: one base robot maps M zones, each reachable by 3 of H
  helpers that must localise themselves (laser or camera): a covering whose
  optimal covers tie when M is 1 more than a multiple of 3, and the nodes
  double with every 3 zones;
- ``mutual(N)``: ``get-a`` and ``get-b`` recurse into each other across N
  robots; ``-k 1`` is fast, ``--all`` grows much faster than N!;
- ``triangulate(N, rooms)``: a robot located by three distinct observers in
  its room, a precondition that joins ``robot`` three times with ``in`` four
  times: N^3 bindings, each matched and priced;
- ``pairs(N, bars)``: bars carried by two robots whose batteries add up to
  120, filtered by negations and ``eval``: N^2 pairs, most refused.
"""

from __future__ import annotations


def _state(facts: list[str], goal: str) -> str:
    return "(state " + "\n       ".join(facts) + f")\n(goal {goal})\n"


def overlap(m: int, h: int | None = None) -> tuple[str, str]:
    """Domain and state text: ``m`` zones, ``h`` helpers (at least 3; ``m`` if None)."""
    helpers = max(3, m if h is None else h)
    zones = range(1, m + 1)
    reports = " ".join(f"(report Z{z} ?b)" for z in zones)
    body = " ".join(f"(?g{z} (get-report Z{z} ?b))" for z in zones)
    wires = " ".join(f"((local ?b) ?g{z} ?f (report Z{z} ?b))" for z in zones)
    domain = f""";;; Overlap (benchmarks/families/weak.py): {m} zones, {helpers} helpers.
(make-functionality :name '(laser ?r) :precond '((laser ?r)) :out '((scan ?r)))
(make-functionality :name '(camera ?r) :precond '((camera ?r)) :out '((image ?r)))
(make-functionality :name '(scan-loc ?r) :in '((scan ?r)) :out '((pose ?r)))
(make-functionality :name '(marker-loc ?r) :in '((image ?r)) :out '((pose ?r)))
(make-functionality :name '(explore ?h ?z) :in '((pose ?h)) :out '((report ?z ?h)))
(make-functionality :name '(receive ?b ?h ?z) :in '((report ?z ?h)) :out '((report ?z ?b)))
(make-functionality :name '(build-map ?b) :in '({reports}))
(make-config-method :name '(localize ?r) :precond '((laser ?r))
  :out '((?l (pose ?r))) :channels '(((local ?r) ?s ?l (scan ?r)))
  :body '((?s (laser ?r)) (?l (scan-loc ?r))))
(make-config-method :name '(localize ?r) :precond '((camera ?r))
  :out '((?l (pose ?r))) :channels '(((local ?r) ?s ?l (image ?r)))
  :body '((?s (camera ?r)) (?l (marker-loc ?r))))
(make-config-method :name '(get-report ?z ?b) :precond '((reach ?h ?z))
  :out '((?x (report ?z ?b)))
  :channels '(((local ?h) ?l ?e (pose ?h)) ((global ?h ?b) ?e ?x (report ?z ?h)))
  :body '((?l (localize ?h)) (?e (explore ?h ?z)) (?x (receive ?b ?h ?z))))
(make-config-method :name '(do-map ?b) :precond '((base ?b))
  :channels '({wires})
  :body '((?f (build-map ?b)) {body}))
"""
    facts = ["(robot B)", "(base B)"]
    for i in range(1, helpers + 1):
        facts += [f"(robot H{i})", f"(laser H{i})" if i % 2 else f"(camera H{i})"]
        facts += [f"(camera H{i})"] if i % 3 == 0 else []
    facts += [f"(reach H{(z + j - 1) % helpers + 1} Z{z})" for z in zones for j in range(3)]
    return domain, _state(facts, "(do-map B)")


def mutual(n: int) -> tuple[str, str]:
    """Domain and state text: ``n`` robots, only the last senses ``a``."""
    domain = f""";;; Mutual recursion (benchmarks/families/weak.py): {n} robots.
(make-functionality :name '(sense-a ?r) :precond '((sensor ?r)) :out '((a ?r)))
(make-functionality :name '(a-from-b ?r ?s) :in '((b ?s)) :out '((a ?r)))
(make-functionality :name '(b-from-a ?r ?s) :in '((a ?s)) :out '((b ?r)))
(make-functionality :name '(convert ?r) :in '((a ?r)) :out '((b ?r)) :cost 2)
(make-functionality :name '(act ?r) :in '((a ?r)))
(make-config-method :name '(get-a ?r) :precond '((sensor ?r))
  :out '((?x (a ?r))) :body '((?x (sense-a ?r))))
(make-config-method :name '(get-a ?r) :precond '((robot ?s) (eval (not (eql '?s '?r))))
  :out '((?y (a ?r))) :channels '(((global ?s ?r) ?x ?y (b ?s)))
  :body '((?x (get-b ?s)) (?y (a-from-b ?r ?s))))
(make-config-method :name '(get-b ?r) :precond '((robot ?s) (eval (not (eql '?s '?r))))
  :out '((?y (b ?r))) :channels '(((global ?s ?r) ?x ?y (a ?s)))
  :body '((?x (get-a ?s)) (?y (b-from-a ?r ?s))))
(make-config-method :name '(get-b ?r)
  :out '((?y (b ?r))) :channels '(((local ?r) ?x ?y (a ?r)))
  :body '((?x (get-a ?r)) (?y (convert ?r))))
(make-config-method :name '(task ?r) :channels '(((local ?r) ?g ?c (a ?r)))
  :body '((?g (get-a ?r)) (?c (act ?r))))
"""
    facts = [f"(robot R{i})" for i in range(1, n + 1)] + [f"(sensor R{n})"]
    return domain, _state(facts, "(task R1)")


def triangulate(n: int, rooms: int = 2) -> tuple[str, str]:
    """Domain and state text: ``n`` robots over ``rooms`` rooms; R1 is located."""
    domain = f""";;; Triangulate (benchmarks/families/weak.py): {n} robots, {rooms} rooms.
(make-functionality :name '(camera ?r) :precond '((camera ?r)) :out '((image ?r)))
(make-functionality :name '(laser ?r) :precond '((laser ?r)) :out '((scan ?r)))
(make-functionality :name '(bearing-cam ?a ?t) :in '((image ?a)) :out '((bearing ?a ?t)))
(make-functionality :name '(bearing-laser ?a ?t) :in '((scan ?a)) :out '((bearing ?a ?t)))
(make-functionality :name '(triangulate ?t ?a ?b ?c)
  :in '((bearing ?a ?t) (bearing ?b ?t) (bearing ?c ?t)) :out '((pos ?t)))
(make-functionality :name '(go-to ?t) :in '((pos ?t)))
(make-config-method :name '(get-bearing ?a ?t) :precond '((camera ?a))
  :out '((?b (bearing ?a ?t))) :channels '(((local ?a) ?c ?b (image ?a)))
  :body '((?c (camera ?a)) (?b (bearing-cam ?a ?t))))
(make-config-method :name '(get-bearing ?a ?t) :precond '((laser ?a))
  :out '((?b (bearing ?a ?t))) :channels '(((local ?a) ?c ?b (scan ?a)))
  :body '((?c (laser ?a)) (?b (bearing-laser ?a ?t))))
(make-config-method :name '(locate ?t)
  :precond '((robot ?a) (robot ?b) (robot ?c) (in ?a ?x) (in ?b ?x) (in ?c ?x) (in ?t ?x)
             (eval (not (eql '?a '?b))) (eval (not (eql '?a '?c))) (eval (not (eql '?b '?c)))
             (eval (not (eql '?a '?t))) (eval (not (eql '?b '?t))) (eval (not (eql '?c '?t))))
  :out '((?f (pos ?t)))
  :channels '(((global ?a ?t) ?p ?f (bearing ?a ?t)) ((global ?b ?t) ?q ?f (bearing ?b ?t))
              ((global ?c ?t) ?s ?f (bearing ?c ?t)))
  :body '((?p (get-bearing ?a ?t)) (?q (get-bearing ?b ?t)) (?s (get-bearing ?c ?t))
          (?f (triangulate ?t ?a ?b ?c))))
(make-config-method :name '(do-go ?t) :channels '(((local ?t) ?l ?g (pos ?t)))
  :body '((?l (locate ?t)) (?g (go-to ?t))))
"""
    robots = [f"R{i}" for i in range(1, n + 1)]
    facts = [f"(robot {r})" for r in robots]
    facts += [f"(in {r} Room{i % rooms + 1})" for i, r in enumerate(robots)]
    facts += [f"(camera {r})" for r in robots[::2]] + [f"(laser {r})" for r in robots[::3]]
    return domain, _state(facts, "(do-go R1)")


def pairs(n: int, bars: int = 2) -> tuple[str, str]:
    """Domain and state text: ``bars`` bars, ``n`` robots (some busy or broken)."""
    body = " ".join(f"(?c{i} (carry Bar{i}))" for i in range(1, bars + 1))
    domain = f""";;; Pairs (benchmarks/families/weak.py): {bars} bars, {n} robots.
(make-functionality :name '(sonar ?r) :out '((sonar ?r)))
(make-functionality :name '(laser ?r) :precond '((laser ?r)) :out '((scan ?r)))
(make-functionality :name '(loc-sonar ?r) :in '((sonar ?r)) :out '((pose ?r)) :cost 3)
(make-functionality :name '(loc-laser ?r) :in '((scan ?r)) :out '((pose ?r)))
(make-functionality :name '(hold ?r ?x ?o) :in '((pose ?r) (pose ?o)))
(make-config-method :name '(get-pose ?r) :precond '((laser ?r))
  :out '((?l (pose ?r))) :channels '(((local ?r) ?s ?l (scan ?r)))
  :body '((?s (laser ?r)) (?l (loc-laser ?r))))
(make-config-method :name '(get-pose ?r)
  :out '((?l (pose ?r))) :channels '(((local ?r) ?s ?l (sonar ?r)))
  :body '((?s (sonar ?r)) (?l (loc-sonar ?r))))
(make-config-method :name '(carry ?x)
  :precond '((robot ?h) (robot ?g) (eval (not (eql '?h '?g)))
             (not (busy ?h)) (not (busy ?g)) (not (broken ?h)) (not (broken ?g))
             (battery ?h ?bh) (battery ?g ?bg) (eval (>= (+ ?bh ?bg) 120))
             (in ?x ?room) (in ?h ?room) (in ?g ?room))
  :channels '(((local ?h) ?p ?a (pose ?h)) ((local ?g) ?q ?b (pose ?g))
              ((global ?g ?h) ?q ?a (pose ?g)) ((global ?h ?g) ?p ?b (pose ?h)))
  :body '((?p (get-pose ?h)) (?q (get-pose ?g)) (?a (hold ?h ?x ?g)) (?b (hold ?g ?x ?h))))
(make-config-method :name '(carry-all) :body '({body}))
"""
    facts = []
    for i in range(1, n + 1):
        r = f"R{i}"
        facts += [f"(robot {r})", f"(battery {r} {(i * 37) % 100})", f"(in {r} Room{i % 2 + 1})"]
        facts += [f"(busy {r})"] if i % 3 == 0 else []
        facts += [f"(broken {r})"] if i % 4 == 2 else []
        facts += [f"(laser {r})"] if i % 5 == 0 else []
    facts += [f"(in Bar{i} Room{i % 2 + 1})" for i in range(1, bars + 1)]
    return domain, _state(facts, "(carry-all)")
