;;; Carry a bar, section 6.3.2 after the laser fails: the laser is removed.
;;; The thesis reports two configurations of cost 45.
(state robot(Pippi), robot(Emil), sonar(Pippi), sonar(Emil),
       odometer(Pippi), odometer(Emil), in(Pippi, Room1), in(Emil, Room1))

(goal (do-carry-bar Pippi))
