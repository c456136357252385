;;; As state-kitchen.lisp, but Vacu's own laser has failed: Robby's laser or the
;;; ceiling camera must tell Vacu where it is, over a global channel.
(state (robot Vacu) (robot Robby) (device CamKitchen)
       (laser Robby) (camera CamKitchen)
       (station Charger1)
       (in Vacu Kitchen) (in Robby Kitchen) (in CamKitchen Kitchen) (in Charger1 Kitchen))
(goal (do-dock Vacu Charger1))
