;;; Cross a door, section 6.2.2 step 2: Pippi has crossed and waits in Room2;
;;; now Emil crosses. The door stands between the two rooms, so it is in both.
;;; The thesis reports the configurations of step 1 with roles exchanged (44, 47).
(state (robot Pippi) (robot Emil) (door Door1)
       (camera Emil) (camera Pippi) (compass Pippi) (compass Emil)
       (in Pippi Room2) (in Emil Room1) (in Door1 Room1) (in Door1 Room2)
       (open Door1) (connects Door1 Room1 Room2))

(goal (do-cross-door Emil Door1))
