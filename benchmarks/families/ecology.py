"""``ecology(N, R, C)``: a convoy in a home of R rooms (PEIS-ecology style).

Robots R1..RN stand in rooms Room1..RoomR in turn; C ceiling cameras
Cam1..CamC, declared devices, hang in the rooms in turn. Every third robot
carries a laser, every other one a camera. The convoy is all N robots, led
by R1: each member needs its own pose to follow — from its own laser, from a
ceiling camera in its room, or from another robot's camera in its room (the
camera's host computes the pose and sends it over a global channel to a
receiver on the member) — and the leader also the pose of Door1, from its own
camera or from any camera in its room. A camera serves every member it
tracks, so the cheapest configuration picks few camera hosts per room: a
covering problem, with many equal-cost alternatives.

``media_tight(N, R, C)`` adds an obstacle map per member: from its own laser,
or from a camera in its room that either streams raw images (bandwidth 40,
the map built on the member) or builds the map on board (one more
functionality, bandwidth 5). Every camera host has a medium of capacity 40 to
every member in its room: a member that takes the raw stream from a host
cannot also take its pose (5) from that host, so the derivations that are
cheapest on functionalities are communication-inadmissible.
"""

from __future__ import annotations

from itertools import pairwise

POSE = """\
;;; Ecology (benchmarks/families/ecology.py): a convoy of {n} robots, {r} rooms, {c} cameras.
(make-functionality :name '(laser ?r) :precond '((laser ?r)) :out '((scan ?r)))
(make-functionality :name '(camera ?c) :precond '((camera ?c)) :out '((image ?c)))
(make-functionality :name '(localize ?r) :in '((scan ?r)) :out '((pose ?r)))
(make-functionality :name '(track ?c ?r) :in '((image ?c)) :out '((seen ?c ?r)))
(make-functionality :name '(receive-pose ?r ?c) :in '((seen ?c ?r)) :out '((pose ?r)))
(make-functionality :name '(detect-door ?c ?d) :in '((image ?c)) :out '((door ?c ?d)))
(make-functionality :name '(receive-door ?r ?c ?d) :in '((door ?c ?d)) :out '((door ?r ?d)))
(make-functionality :name '(lead ?r ?d) :in '((pose ?r) (door ?r ?d)))
(make-functionality :name '(follow ?r) :in '((pose ?r)))

(make-config-method :name '(get-pose ?r) :precond '((laser ?r))
  :out '((?l (pose ?r))) :channels '(((local ?r) ?s ?l (scan ?r)))
  :body '((?s (laser ?r)) (?l (localize ?r))))
(make-config-method :name '(get-pose ?r)
  :precond '((in ?r ?room) (device ?c) (camera ?c) (in ?c ?room))
  :out '((?p (pose ?r)))
  :channels '(((local ?c) ?i ?t (image ?c)) ((global ?c ?r) ?t ?p (seen ?c ?r) 5))
  :body '((?i (camera ?c)) (?t (track ?c ?r)) (?p (receive-pose ?r ?c))))
(make-config-method :name '(get-pose ?r)
  :precond '((in ?r ?room) (robot ?c) (camera ?c) (in ?c ?room) (eval (not (eql '?c '?r))))
  :out '((?p (pose ?r)))
  :channels '(((local ?c) ?i ?t (image ?c)) ((global ?c ?r) ?t ?p (seen ?c ?r) 5))
  :body '((?i (camera ?c)) (?t (track ?c ?r)) (?p (receive-pose ?r ?c))))

(make-config-method :name '(get-door ?r ?d) :precond '((camera ?r))
  :out '((?t (door ?r ?d))) :channels '(((local ?r) ?i ?t (image ?r)))
  :body '((?i (camera ?r)) (?t (detect-door ?r ?d))))
(make-config-method :name '(get-door ?r ?d)
  :precond '((in ?r ?room) (camera ?c) (in ?c ?room) (eval (not (eql '?c '?r))))
  :out '((?p (door ?r ?d)))
  :channels '(((local ?c) ?i ?t (image ?c)) ((global ?c ?r) ?t ?p (door ?c ?d) 5))
  :body '((?i (camera ?c)) (?t (detect-door ?c ?d)) (?p (receive-door ?r ?c ?d))))

(make-config-method :name '(convoy ?r) :precond '((next ?r ?s))
  :channels '(((local ?r) ?p ?f (pose ?r)))
  :body '((?p (get-pose ?r)) (?f (follow ?r)) (?n (convoy ?s))))
(make-config-method :name '(convoy ?r) :precond '((last ?r))
  :channels '(((local ?r) ?p ?f (pose ?r)))
  :body '((?p (get-pose ?r)) (?f (follow ?r))))
(make-config-method :name '(do-convoy ?r ?d) :precond '((next ?r ?s))
  :channels '(((local ?r) ?p ?l (pose ?r)) ((local ?r) ?g ?l (door ?r ?d)))
  :body '((?p (get-pose ?r)) (?g (get-door ?r ?d)) (?l (lead ?r ?d)) (?n (convoy ?s))))
"""

MAP = """
(make-functionality :name '(scan-map ?r) :in '((scan ?r)) :out '((map ?r)))
(make-functionality :name '(image-map ?r ?c) :in '((image ?c)) :out '((map ?r)))
(make-functionality :name '(onboard-map ?c ?r) :in '((image ?c)) :out '((map-of ?c ?r)))
(make-functionality :name '(receive-map ?r ?c) :in '((map-of ?c ?r)) :out '((map ?r)))
(make-functionality :name '(avoid ?r) :in '((map ?r) (pose ?r)))

(make-config-method :name '(get-map ?r) :precond '((laser ?r))
  :out '((?m (map ?r))) :channels '(((local ?r) ?s ?m (scan ?r)))
  :body '((?s (laser ?r)) (?m (scan-map ?r))))
(make-config-method :name '(get-map ?r)
  :precond '((in ?r ?room) (camera ?c) (in ?c ?room) (eval (not (eql '?c '?r))))
  :out '((?m (map ?r))) :channels '(((global ?c ?r) ?i ?m (image ?c) 40))
  :body '((?i (camera ?c)) (?m (image-map ?r ?c))))
(make-config-method :name '(get-map ?r)
  :precond '((in ?r ?room) (camera ?c) (in ?c ?room) (eval (not (eql '?c '?r))))
  :out '((?p (map ?r)))
  :channels '(((local ?c) ?i ?o (image ?c)) ((global ?c ?r) ?o ?p (map-of ?c ?r) 5))
  :body '((?i (camera ?c)) (?o (onboard-map ?c ?r)) (?p (receive-map ?r ?c))))
(make-config-method :name '(get-map ?r) :precond '((camera ?r))
  :out '((?m (map ?r))) :channels '(((local ?r) ?i ?m (image ?r)))
  :body '((?i (camera ?r)) (?m (image-map ?r ?r))))

(make-config-method :name '(safe ?r) :precond '((next ?r ?s))
  :channels '(((local ?r) ?p ?a (pose ?r)) ((local ?r) ?m ?a (map ?r)))
  :body '((?p (get-pose ?r)) (?m (get-map ?r)) (?a (avoid ?r)) (?n (safe ?s))))
(make-config-method :name '(safe ?r) :precond '((last ?r))
  :channels '(((local ?r) ?p ?a (pose ?r)) ((local ?r) ?m ?a (map ?r)))
  :body '((?p (get-pose ?r)) (?m (get-map ?r)) (?a (avoid ?r))))
(make-config-method :name '(do-safe-convoy ?r ?d)
  :body '((?c (do-convoy ?r ?d)) (?s (safe ?r))))
"""


def _world(n: int, rooms: int, cameras: int, media: bool) -> list[str]:
    if n < 2 or rooms < 1 or cameras < 0:
        raise ValueError("need N >= 2 robots, R >= 1 rooms, C >= 0 cameras")
    robots = [f"R{i}" for i in range(1, n + 1)]
    cams = [f"Cam{j}" for j in range(1, cameras + 1)]
    room = {a: f"Room{i % rooms + 1}" for i, a in enumerate(robots)}
    room.update({c: f"Room{j % rooms + 1}" for j, c in enumerate(cams)})
    facts = [f"(robot {r})" for r in robots] + [f"(device {c})" for c in cams]
    facts += [f"(camera {c})" for c in cams]
    facts += [f"(laser {r})" for i, r in enumerate(robots) if i % 3 == 2]
    facts += [f"(camera {r})" for i, r in enumerate(robots) if i % 2 == 1]
    facts += [f"(in {a} {room[a]})" for a in [*robots, *cams]]
    facts += [f"(next {a} {b})" for a, b in pairwise(robots)]
    facts += [f"(last {robots[-1]})", f"(in Door1 {room['R1']})"]
    if media:  # every camera host to every member of its room
        hosts = cams + [r for i, r in enumerate(robots) if i % 2 == 1]
        facts += [
            f"(medium wifi {h} {r} 40)"
            for h in hosts
            for r in robots
            if h != r and room[h] == room[r]
        ]
    return facts


def _state(facts: list[str], goal: str) -> str:
    return "(state " + "\n       ".join(facts) + f")\n(goal {goal})\n"


def ecology(n: int, rooms: int, cameras: int) -> tuple[str, str]:
    """Domain and state text: a convoy of ``n`` robots over ``rooms`` rooms."""
    domain = POSE.format(n=n, r=rooms, c=cameras)
    return domain, _state(_world(n, rooms, cameras, media=False), "(do-convoy R1 Door1)")


def media_tight(n: int, rooms: int, cameras: int) -> tuple[str, str]:
    """Domain and state text: the convoy, each member also needing an obstacle map."""
    domain = POSE.format(n=n, r=rooms, c=cameras) + MAP
    return domain, _state(_world(n, rooms, cameras, media=True), "(do-safe-convoy R1 Door1)")
