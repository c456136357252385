"""``gateway(N, D)``: N robots each watch a view cropped from one of D ceiling
cameras and forwarded through a hub, or from a camera of their own.

Every camera's link to the hub (capacity 40) carries one view (30): the
cheap derivations, where robots share a camera, are communication-inadmissible,
and every one-to-one assignment of robots to cameras is admissible. Robots
R1, R3, ... have a camera of their own too, at ``:cost 25``: with fewer
cameras than robots (``D < N``) some of them must use it. A bound that
believes every robot can share the cheapest camera tries the partial
assignments (factorial in N) before its first configuration; the media cap
on sharing (:mod:`cfgplan.planner.partition`) knows each robot pays for one.
"""

from __future__ import annotations


def gateway(n: int, d: int | None = None, capacity: int = 40) -> tuple[str, str]:
    """Domain and state text: ``n`` robots, ``d`` cameras (``n`` if None)."""
    cameras = n if d is None else d
    if n < 1 or cameras < 0:
        raise ValueError("need N >= 1 and D >= 0")
    robots = [f"R{i}" for i in range(1, n + 1)]
    domain = f""";;; Gateway (benchmarks/families/gateway.py): {n} robots, {cameras} cameras.
(make-functionality :name '(camera ?c) :precond '((camera ?c)) :out '((image ?c)))
(make-functionality :name '(crop ?c ?r) :in '((image ?c)) :out '((view ?c ?r)))
(make-functionality :name '(forward ?h ?c ?r) :in '((view ?c ?r)) :out '((view ?r)))
(make-functionality :name '(deliver ?r ?h) :in '((view ?r)) :out '((view ?r)))
(make-functionality :name '(own-view ?r) :precond '((camera ?r)) :in '((image ?r))
  :out '((view ?r)) :cost 25)
(make-functionality :name '(watch ?r) :in '((view ?r)) :out '((done ?r)))
(make-config-method :name '(get-view ?r)
  :precond '((hub ?h) (device ?c) (camera ?c))
  :out '((?f (view ?r)))
  :channels '(((local ?c) ?i ?k (image ?c)) ((global ?c ?h) ?k ?w (view ?c ?r) 30)
              ((global ?h ?r) ?w ?f (view ?r) 30))
  :body '((?i (camera ?c)) (?k (crop ?c ?r)) (?w (forward ?h ?c ?r)) (?f (deliver ?r ?h))))
(make-config-method :name '(get-view ?r) :precond '((camera ?r))
  :out '((?o (view ?r))) :channels '(((local ?r) ?i ?o (image ?r)))
  :body '((?i (camera ?r)) (?o (own-view ?r))))
(make-config-method :name '(watch-one ?r) :out '((?w (done ?r)))
  :channels '(((local ?r) ?v ?w (view ?r)))
  :body '((?v (get-view ?r)) (?w (watch ?r))))
(make-functionality :name '(supervise ?b) :in '({" ".join(f"(done {r})" for r in robots)}))
(make-config-method :name '(watch-all ?b)
  :channels '({" ".join(f"((global {r} ?b) ?w{i} ?s (done {r}))" for i, r in enumerate(robots))})
  :body '({" ".join(f"(?w{i} (watch-one {r}))" for i, r in enumerate(robots))} (?s (supervise ?b))))
"""
    cams = [f"Cam{j}" for j in range(1, cameras + 1)]
    facts = ["(robot Base)", "(robot Hub)", "(hub Hub)"] + [f"(robot {r})" for r in robots]
    facts += [f"(device {c})" for c in cams] + [f"(camera {c})" for c in cams]
    facts += [f"(camera {r})" for r in robots[::2]]
    facts += [f"(medium wire {c} Hub {capacity})" for c in cams]
    facts += [f"(medium wifi Hub {r} 1000)" for r in robots]
    facts += [f"(medium wifi {r} Base 100)" for r in robots]
    state = "(state " + "\n       ".join(facts) + ")\n(goal (watch-all Base))\n"
    return domain, state
