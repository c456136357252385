;;; Section 6.2.2 as one sequence (with domain-steps.lisp): Pippi crosses Door1
;;; with Emil's help, then Emil crosses with Pippi's, who now stands in Room2.
;;; The door is in both rooms, as a door between two rooms is (the thesis's
;;; step 3 puts it only in Room1, where no configuration exists then).
(state robot(Pippi), robot(Emil), door(Door1), camera(Emil), camera(Pippi),
       compass(Pippi), compass(Emil), in(Pippi, Room1), in(Emil, Room1),
       in(Door1, Room1), in(Door1, Room2), open(Door1),
       connects(Door1, Room1, Room2), connects(Door1, Room2, Room1))

(sequence (do-cross-door Pippi Door1)
          (do-cross-door Emil Door1))
