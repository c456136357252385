;;; Docking at home: an example beyond the thesis (README, "Devices and adaptive channels").
;;;
;;; A robot that must dock needs its pose. Whatever is in its room may give it:
;;; its own laser, another robot's laser, or a ceiling camera, which the state
;;; declares a (device ...), not a robot. The channel that brings the pose is
;;; (any ?h ?r): local when ?h is the docking robot itself, global otherwise,
;;; so one version of do-dock covers all three.

(make-functionality :name '(laser ?h) :precond '((laser ?h)) :out '((scan ?h)))
(make-functionality :name '(camera ?h) :precond '((camera ?h)) :out '((image ?h)))
(make-functionality :name '(scan-match ?h ?r) :in '((scan ?h)) :out '((pose ?r)))
(make-functionality :name '(track ?h ?r) :in '((image ?h)) :out '((pose ?r)))
(make-functionality :name '(dock ?r ?s) :in '((pose ?r)))

;; ?h localizes ?r with its laser (?h may be ?r itself)
(make-config-method :name '(get-pose ?h ?r)
  :precond '((laser ?h))
  :out '((?m (pose ?r) 5))
  :channels '(((local ?h) ?l ?m (scan ?h)))
  :body '((?l (laser ?h)) (?m (scan-match ?h ?r))))

;; ?h's camera tracks ?r
(make-config-method :name '(get-pose ?h ?r)
  :precond '((camera ?h))
  :out '((?t (pose ?r) 5))
  :channels '(((local ?h) ?c ?t (image ?h)))
  :body '((?c (camera ?h)) (?t (track ?h ?r))))

(make-config-method :name '(do-dock ?r ?s)
  :precond '((robot ?r) (station ?s) (in ?r ?room) (in ?s ?room) (in ?h ?room))
  :channels '(((any ?h ?r) ?p ?d (pose ?r)))
  :body '((?p (get-pose ?h ?r)) (?d (dock ?r ?s))))
