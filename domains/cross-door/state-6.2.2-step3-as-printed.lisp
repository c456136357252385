;;; Cross a door, section 6.2.2 step 3 exactly as printed: the door is only in
;;; Room1. Pippi (in Room2) cannot observe it, so no configuration is
;;; admissible; cfgplan says which precondition failed: (in Door1 ?room).
(state robot(Pippi), robot(Emil), door(Door1), camera(Emil), camera(Pippi),
       in(Pippi, Room2), in(Emil, Room1), in(Door1, Room1), open(Door1),
       connects(Door1, Room1, Room2))

(goal (do-cross-door Emil Door1))
