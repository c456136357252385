;;; Cross a door, section 6.2.2 step 1, in the thesis's printed notation.
;;; Pippi and Emil are in Room1; Pippi is to cross Door1 with Emil's help.
;;; The thesis reports two configurations, costs 44 and 47.
(state robot(Pippi), robot(Emil), door(Door1), camera(Emil), camera(Pippi),
       compass(Pippi), compass(Emil), in(Pippi, Room1), in(Emil, Room1),
       in(Door1, Room1), open(Door1), connects(Door1, Room1, Room2))

(goal (do-cross-door Pippi Door1))
