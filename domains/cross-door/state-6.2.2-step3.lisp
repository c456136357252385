;;; Cross a door, section 6.2.2 step 3: Emil's compass is disturbed, so the
;;; compasses are removed from the state. The thesis reports only the camera
;;; configuration (cost 47). It prints the door only in Room1; then Pippi, in
;;; Room2, cannot see it and nothing is admissible (state-6.2.2-step3-as-printed.lisp).
;;; A door between two rooms is in both, as here.
(state (robot Pippi) (robot Emil) (door Door1) (camera Emil) (camera Pippi)
       (in Pippi Room2) (in Emil Room1) (in Door1 Room1) (in Door1 Room2)
       (open Door1) (connects Door1 Room1 Room2))

(goal (do-cross-door Emil Door1))
