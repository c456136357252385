"""``delegation(N)``: recursive delegation among N robots.

``(get ?r)`` senses on ``?r`` (only RN can), delegates to ``(get ?s)`` on
any other robot ``?s`` (which sends the datum back over a global channel to a
relay on ``?r``), or, on the hub R1, merges what two other robots ``?s`` and
``?t`` get. The recursion guard of 4.5 prunes a method instance only on its
own expansion path, so the same ``(get ?s)`` is expanded again under every
arrangement of its ancestors: the derivation tree grows much faster than N!,
while the configurations are the chains of relays that reach RN, alone or
two by two.
"""

from __future__ import annotations


def delegation(n: int) -> tuple[str, str]:
    """Domain and state text with ``n`` robots."""
    if n < 2:
        raise ValueError("need N >= 2")
    domain = f""";;; Recursive delegation (benchmarks/families/delegation.py): {n} robots.
(make-functionality :name '(sense ?r) :precond '((sensor ?r)) :out '((d ?r)))
(make-functionality :name '(relay ?r ?s) :in '((d ?s)) :out '((d ?r)))
(make-functionality :name '(merge ?r ?s ?t) :in '((d ?s) (d ?t)) :out '((d ?r)))
(make-functionality :name '(act ?r) :in '((d ?r)))
(make-config-method :name '(get ?r) :precond '((sensor ?r))
  :out '((?a (d ?r))) :body '((?a (sense ?r))))
(make-config-method :name '(get ?r) :precond '((robot ?s) (eval (not (eql '?s '?r))))
  :out '((?b (d ?r))) :channels '(((global ?s ?r) ?a ?b (d ?s)))
  :body '((?a (get ?s)) (?b (relay ?r ?s))))
(make-config-method :name '(get ?r)
  :precond '((hub ?r) (robot ?s) (robot ?t) (eval (not (eql '?s '?r)))
             (eval (not (eql '?t '?r))) (eval (not (eql '?s '?t))))
  :out '((?m (d ?r)))
  :channels '(((global ?s ?r) ?a ?m (d ?s)) ((global ?t ?r) ?b ?m (d ?t)))
  :body '((?a (get ?s)) (?b (get ?t)) (?m (merge ?r ?s ?t))))
(make-config-method :name '(task ?r) :channels '(((local ?r) ?g ?a (d ?r)))
  :body '((?g (get ?r)) (?a (act ?r))))
"""
    facts = [f"(robot R{i})" for i in range(1, n + 1)] + [f"(sensor R{n})", "(hub R1)"]
    state = "(state " + " ".join(facts) + ")\n(goal (task R1))\n"
    return domain, state


def any_delegation(n: int) -> tuple[str, str]:
    """Domain and state text with ``n`` robots: one generic ``get`` that any
    robot may delegate to any other, which may delegate again, pruned only by
    recursion on its own path; only R2 has a camera, and the datum must come
    back along local channels, so every delegation chain but the direct one
    is a dead end found at its last step. One configuration (cost 30),
    whatever ``n``."""
    if n < 2:
        raise ValueError("need N >= 2")
    domain = f""";;; Delegation to any robot (benchmarks/families/delegation.py): {n} robots.
(make-functionality :name '(s ?r) :out '((d ?r)))
(make-functionality :name '(p ?r ?o) :in '((d ?r)) :out '((e ?r ?o)))
(make-functionality :name '(t ?h ?r ?o) :in '((e ?h ?o) (d ?h)) :out '((e ?r ?o)))
(make-functionality :name '(act ?r ?o) :in '((e ?r ?o)))
(make-config-method :name '(get ?r ?o) :precond '((cam ?r))
  :out '((?f2 (e ?r ?o))) :channels '(((local ?r) ?f1 ?f2 (d ?r)))
  :body '((?f1 (s ?r)) (?f2 (p ?r ?o))))
(make-config-method :name '(get ?r ?o)
  :precond '((robot ?h) (eval (not (eql (quote ?r) (quote ?h)))))
  :out '((?f1 (e ?r ?o))) :body '((?f1 (get ?h ?r ?o))))
(make-config-method :name '(get ?h ?r ?o)
  :precond '((robot ?x) (eval (not (eql (quote ?x) (quote ?h)))))
  :out '((?f1 (e ?r ?o))) :body '((?f1 (get ?x ?r ?o))))
(make-config-method :name '(get ?h ?r ?o)
  :out '((?f3 (e ?r ?o)))
  :channels '(((local ?h) ?f1 ?f3 (e ?h ?o)) ((local ?h) ?f2 ?f3 (d ?h)))
  :body '((?f1 (get ?h ?o)) (?f2 (s ?h)) (?f3 (t ?h ?r ?o))))
(make-config-method :name '(do ?r ?o)
  :precond '((robot ?h) (eval (not (eql (quote ?r) (quote ?h)))))
  :channels '(((global ?h ?r) ?f1 ?f2 (e ?r ?o)))
  :body '((?f1 (get ?h ?r ?o)) (?f2 (act ?r ?o))))
"""
    facts = [f"(robot r{i})" for i in range(1, n + 1)] + ["(cam r2)", "(object o1)"]
    state = "(state " + " ".join(facts) + ")\n(goal (do r1 o1))\n"
    return domain, state
