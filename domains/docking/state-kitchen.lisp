;;; Vacu docks at Charger1 in the kitchen, where Robby and a ceiling camera are too.
(state (robot Vacu) (robot Robby) (device CamKitchen)
       (laser Vacu) (laser Robby) (camera CamKitchen)
       (station Charger1)
       (in Vacu Kitchen) (in Robby Kitchen) (in CamKitchen Kitchen) (in Charger1 Kitchen))
(goal (do-dock Vacu Charger1))
