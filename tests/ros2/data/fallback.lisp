;;; A robot that drives on a laser, or on a sonar when the laser fails (the
;;; ros2 test set): both are ROS 2 topics (/scan, /sonar), the drive a topic
;;; (/cmd_vel); avoid is Python (drive_impl.py). The laser is cheaper, so it
;;; runs first; its topic stopping is a failure, and the society switches.
(make-functionality :name '(laser ?r) :precond '((laser ?r)) :out '((scan ?r)) :cost 1)
(make-functionality :name '(sonar ?r) :precond '((sonar ?r)) :out '((scan ?r)) :cost 5)
(make-functionality :name '(avoid ?r) :in '((scan ?r)) :out '((cmd ?r)))
(make-functionality :name '(drive ?r) :in '((cmd ?r)))

(make-config-method :name '(see ?r)
  :precond '((laser ?r))
  :out '((?f1 (scan ?r)))
  :body '((?f1 (laser ?r))))
(make-config-method :name '(see ?r)
  :precond '((sonar ?r))
  :out '((?f1 (scan ?r)))
  :body '((?f1 (sonar ?r))))

(make-config-method :name '(do-drive ?r)
  :precond '((robot ?r))
  :channels '(((local ?r) ?f1 ?f2 (scan ?r))
              ((local ?r) ?f2 ?f3 (cmd ?r)))
  :body '((?f1 (see ?r)) (?f2 (avoid ?r)) (?f3 (drive ?r))))
