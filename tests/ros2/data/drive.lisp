;;; A robot that drives on its laser scans (tests of the ROS 2 bindings): the laser is a
;;; ROS 2 topic (/scan), the drive a ROS 2 topic (/cmd_vel); avoid is Python.
(make-functionality :name '(laser ?r) :precond '((laser ?r)) :out '((scan ?r)))
(make-functionality :name '(avoid ?r) :in '((scan ?r)) :out '((cmd ?r)))
(make-functionality :name '(drive ?r) :in '((cmd ?r)))

(make-config-method :name '(do-drive ?r)
  :precond '((robot ?r) (laser ?r))
  :channels '(((local ?r) ?f1 ?f2 (scan ?r))
              ((local ?r) ?f2 ?f3 (cmd ?r)))
  :body '((?f1 (laser ?r)) (?f2 (avoid ?r)) (?f3 (drive ?r))))
