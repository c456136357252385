;;; Cross a door with media, section 4.6 (use with domain-bandwidth.lisp).
;;; A socket connection of capacity 200 in each direction between the robots.
(state robot(Pippi), robot(Emil), door(Door1), camera(Emil), camera(Pippi),
       compass(Pippi), compass(Emil), in(Pippi, Room1), in(Emil, Room1),
       in(Door1, Room1), open(Door1), connects(Door1, Room1, Room2),
       medium(socket, Pippi, Emil, 200), medium(socket, Emil, Pippi, 200))

(goal (do-cross-door Pippi Door1))
