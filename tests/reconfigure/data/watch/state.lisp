;;; Pippi keeps the log of what Emil's camera sees of Door1; Rasmus may instead.
(state robot(Pippi), robot(Emil), robot(Rasmus), camera(Emil), door(Door1))

(goal (do-watch Pippi Emil Rasmus Door1))
