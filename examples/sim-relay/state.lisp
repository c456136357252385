;;; A relay through two doors (beyond the thesis): Pippi goes from Room1 to
;;; Room3. Emil, in Room1, guides her through Door1; Rasmus, in Room3, through
;;; Door2. Rasmus has no compass, so the planner gives the second step the
;;; camera configuration (47) where the first has the compasses (44).
(state robot(Pippi), robot(Emil), robot(Rasmus), door(Door1), door(Door2),
       camera(Pippi), camera(Emil), camera(Rasmus), compass(Pippi), compass(Emil),
       in(Pippi, Room1), in(Emil, Room1), in(Rasmus, Room3),
       in(Door1, Room1), in(Door1, Room2), in(Door2, Room2), in(Door2, Room3),
       open(Door1), open(Door2),
       connects(Door1, Room1, Room2), connects(Door1, Room2, Room1),
       connects(Door2, Room2, Room3), connects(Door2, Room3, Room2))

(sequence (do-cross-door Pippi Door1)
          (do-cross-door Pippi Door2))
