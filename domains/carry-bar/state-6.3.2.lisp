;;; Carry a bar, section 6.3.2: Emil has laser, sonars and odometry; Pippi
;;; sonars and odometry. The thesis prints sonars(X) while every method tests
;;; (sonar ?r): read as sonar. Goal: Pippi carries the bar with Emil's help.
(state robot(Pippi), robot(Emil), sonar(Pippi), sonar(Emil),
       odometer(Pippi), odometer(Emil), laser(Emil),
       in(Pippi, Room1), in(Emil, Room1))

(goal (do-carry-bar Pippi))
