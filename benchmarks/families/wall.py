"""``wall(K, N, L)`` generalises build-a-wall (Appendix A.3): a top method with K
pusher roles; every pusher needs block data from some observer robot, which
must carry a laser. Robots R1..RN; the pushers are R1..RK; the last L robots
carry lasers; all have sonars. ``wall(2, 3, 2)`` has the shape of 6.4 (with
Rasmus as R3 and Emil as R2). Derivations: per pusher, L observers x 4 ways
to measure block and wall orientation x 2 ways to measure its own
orientation when it has a laser.
"""

from __future__ import annotations

WALL_DOMAIN = """\
;;; Generalised build-a-wall (benchmarks/families.py): K={k} pushers.
(make-functionality :name '(laser ?r) :out '((laser-reading ?r)))
(make-functionality :name '(sonar ?r) :out '((sonar-reading ?r)))
(make-functionality :name '(push-block ?r ?b ?w)
  :in '((pos ?b ?w) (orient ?b ?w) (orient ?r ?b)))
(make-functionality :name '(measure-orient-laser ?r ?o)
  :in '((laser-reading ?r)) :out '((orient ?r ?o)))
(make-functionality :name '(measure-orient-sonar ?r ?o)
  :in '((sonar-reading ?r)) :out '((orient ?r ?o)))
(make-functionality :name '(measure-pos-laser ?r ?o)
  :in '((laser-reading ?r)) :out '((pos ?r ?o)))
(make-functionality :name '(transform-block-data ?r ?b ?w)
  :in '((pos ?r ?b) (orient ?r ?b) (pos ?r ?w) (orient ?r ?w))
  :out '((pos ?b ?w) (orient ?b ?w)))
(make-config-method :name '(get-block-data ?r ?b ?w)
  :out '((?f5 (pos ?b ?w)) (?f5 (orient ?b ?w)))
  :channels '(((local ?r) ?f1 ?f5 (pos ?r ?b)) ((local ?r) ?f2 ?f5 (orient ?r ?b))
              ((local ?r) ?f3 ?f5 (pos ?r ?w)) ((local ?r) ?f4 ?f5 (orient ?r ?w)))
  :body '((?f1 (get-object-pos ?r ?b)) (?f2 (get-object-orient ?r ?b))
          (?f3 (get-object-pos ?r ?w)) (?f4 (get-object-orient ?r ?w))
          (?f5 (transform-block-data ?r ?b ?w))))
(make-config-method :name '(get-object-orient ?r ?o) :precond '((laser ?r))
  :out '((?f2 (orient ?r ?o))) :channels '(((local ?r) ?f1 ?f2 (laser-reading ?r)))
  :body '((?f1 (laser ?r)) (?f2 (measure-orient-laser ?r ?o))))
(make-config-method :name '(get-object-orient ?r ?o) :precond '((sonar ?r))
  :out '((?f2 (orient ?r ?o))) :channels '(((local ?r) ?f1 ?f2 (sonar-reading ?r)))
  :body '((?f1 (sonar ?r)) (?f2 (measure-orient-sonar ?r ?o))))
(make-config-method :name '(get-object-pos ?r ?o) :precond '((laser ?r))
  :out '((?f2 (pos ?r ?o))) :channels '(((local ?r) ?f1 ?f2 (laser-reading ?r)))
  :body '((?f1 (laser ?r)) (?f2 (measure-pos-laser ?r ?o))))
(make-config-method :name '(do-push ?r ?b ?w) :precond '((pusher ?r) (robot ?robserv))
  :channels '(((local ?r) ?f1 ?f3 (orient ?r ?b))
              ((global ?robserv ?r) ?f2 ?f3 (pos ?b ?w))
              ((global ?robserv ?r) ?f2 ?f3 (orient ?b ?w)))
  :body '((?f1 (get-object-orient ?r ?b)) (?f2 (get-block-data ?robserv ?b ?w))
          (?f3 (push-block ?r ?b ?w))))
(make-config-method :name '(do-push-block ?b ?w)
  :precond '((block ?b) (wall ?w))
  :body '({body}))
"""


def wall(k: int, n: int, lasers: int) -> tuple[str, str]:
    """Domain and state text of the generalised wall with K pushers among N robots, L lasers."""
    if not (1 <= k <= n and 0 <= lasers <= n):
        raise ValueError("need 1 <= K <= N and 0 <= L <= N")
    body = " ".join(f"(?p{i} (do-push R{i} ?b ?w))" for i in range(1, k + 1))
    domain = WALL_DOMAIN.format(k=k, body=body)
    facts = [f"(robot R{i})" for i in range(1, n + 1)]
    facts += [f"(sonar R{i})" for i in range(1, n + 1)]
    facts += [f"(laser R{i})" for i in range(n - lasers + 1, n + 1)]
    facts += [f"(pusher R{i})" for i in range(1, k + 1)]
    facts += ["(block B1)", "(wall W1)"]
    state = "(state " + "\n       ".join(facts) + ")\n(goal (do-push-block B1 W1))\n"
    return domain, state
