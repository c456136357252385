;;; Build a wall, section 6.4: Pippi and Emil push block B1 towards wall W1,
;;; Rasmus may observe. The thesis prints sonars(X) (read as sonar) and gives
;;; no left/right facts although do-push needs them; its numbers (128
;;; derivations, costs 53 to 81) come with Pippi on the left, Emil on the right.
(state robot(Pippi), robot(Emil), robot(Rasmus),
       sonar(Pippi), sonar(Emil), sonar(Rasmus), laser(Emil), laser(Rasmus),
       block(B1), heavy(B1), wall(W1), left(Pippi), right(Emil))

(goal (do-push-block Pippi B1 W1))
