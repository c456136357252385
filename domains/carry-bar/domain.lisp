;;; Carry a bar: Appendix A.2 of R. Lundh, "Plan-Based Configuration of a
;;; Group of Robots" (2006). The PDF interleaves the laser version of
;;; get-global-pos; its text here is de-interleaved by hand.
;;; As printed, with the state of 6.3.2 the planner finds five configurations
;;; (33, 45, 45, 45, 45): two of them localize Emil with the laser. The thesis
;;; reports three; without the laser version of get-global-pos it is exactly
;;; 33, 45, 45.

;; A.2.1 Sensing resources
(make-functionality :name '(laser ?r) :out '((laser-reading ?r)))
(make-functionality :name '(odometer ?r) :out '((odometry ?r)))
(make-functionality :name '(sonar ?r) :out '((sonar-reading ?r)))

;; A.2.2 Action resources
(make-functionality :name '(stalk-robot ?r ?o)
  :in '((angle ?r ?o) (dist ?r ?o) (speed-diff ?r ?o)))
(make-functionality :name '(lead-robot ?r ?o)
  :in '((dist ?o ?r)))

;; A.2.3 Functionalities
;; Measure angle and distance to robot ?o using laser
(make-functionality :name '(meas-robot-angle-dist-laser ?r ?o)
  :in '((laser-reading ?r))
  :out '((angle ?r ?o) (dist ?r ?o)))
; Calculate speed difference between ?r1 and ?r2 using
; distance info. Saves old distance
(make-functionality :name '(calc-robot-speed-diff ?r1 ?r2)
  :in '((dist ?r1 ?r2))
  :out '((speed-diff ?r1 ?r2)))
(make-functionality :name '(localize-sonar ?r)
  :in '((odometry ?r) (sonar-reading ?r))
  :out '((global-pos ?r)))
(make-functionality :name '(localize-laser ?r)
  :in '((odometry ?r) (laser-reading ?r))
  :out '((global-pos ?r)))
; Measure angle and distance to robot ?r2 using global position
(make-functionality :name '(meas-robot-angle-dist-localizer ?r1 ?r2)
  :in '((global-pos ?r1) (global-pos ?r2))
  :out '((angle ?r1 ?r2) (dist ?r1 ?r2)))

;; A.2.4 Methods
; Uses laser to get robot angle and distance
(make-config-method :name '(get-robot-angle-dist ?r1 ?r2)
  :precond '((laser ?r1) (in ?r1 ?room) (in ?r2 ?room) (robot ?r1) (robot ?r2))
  :out '((?f2 (angle ?r1 ?r2)) (?f2 (dist ?r1 ?r2)))
  :channels '(((local ?r1) ?f1 ?f2 (laser-reading ?r1)))
  :body '((?f1 (laser ?r1)) (?f2 (meas-robot-angle-dist-laser ?r1 ?r2))))

; Uses odometer and sonars to get global position
(make-config-method :name '(get-global-pos ?r)
  :precond '((sonar ?r) (odometer ?r) (robot ?r))
  :out '((?f3 (global-pos ?r)))
  :channels '(((local ?r) ?f1 ?f3 (odometry ?r))
              ((local ?r) ?f2 ?f3 (sonar-reading ?r)))
  :body '((?f1 (odometer ?r)) (?f2 (sonar ?r)) (?f3 (localize-sonar ?r))))

; Uses odometer and laser to get global position
(make-config-method :name '(get-global-pos ?r)
  :precond '((laser ?r) (odometer ?r) (robot ?r))
  :out '((?f3 (global-pos ?r)))
  :channels '(((local ?r) ?f1 ?f3 (odometry ?r))
              ((local ?r) ?f2 ?f3 (laser-reading ?r)))
  :body '((?f1 (odometer ?r)) (?f2 (laser ?r)) (?f3 (localize-laser ?r))))

; Uses global position to get angle and distance
(make-config-method :name '(get-robot-angle-dist ?r1 ?r2)
  :precond '((robot ?r1) (robot ?r2) (in ?r1 ?room) (in ?r2 ?room)
             (eval (not (eql (quote ?r1) (quote ?r2)))))
  :out '((?f3 (angle ?r1 ?r2)) (?f3 (dist ?r1 ?r2)))
  :channels '(((local ?r1) ?f1 ?f3 (global-pos ?r1))
              ((global ?r2 ?r1) ?f2 ?f3 (global-pos ?r2)))
  :body '((?f1 (get-global-pos ?r1))
          (?f2 (get-global-pos ?r2))
          (?f3 (meas-robot-angle-dist-localizer ?r1 ?r2))))

; Top method. If we know which robot who should follow and lead
(make-config-method :name '(do-carry-bar ?r2 ?r1)
  :channels '(((local ?r1) ?f1 ?f3 (angle ?r1 ?r2))
              ((local ?r1) ?f1 ?f3 (dist ?r1 ?r2))
              ((local ?r1) ?f1 ?f2 (dist ?r1 ?r2))
              ((local ?r1) ?f2 ?f3 (speed-diff ?r1 ?r2))
              ((global ?r1 ?r2) ?f1 ?f4 (dist ?r1 ?r2)))
  :body '((?f1 (get-robot-angle-dist ?r1 ?r2))
          (?f2 (calc-robot-speed-diff ?r1 ?r2))
          (?f3 (stalk-robot ?r1 ?r2))
          (?f4 (lead-robot ?r2 ?r1))))

; Top method. If we know which robot who should lead
(make-config-method :name '(do-carry-bar ?r2)
  :precond '((robot ?r1) (robot ?r2) (in ?r1 ?room) (in ?r2 ?room)
             (eval (not (eql (quote ?r1) (quote ?r2)))))
  :channels '(((local ?r1) ?f1 ?f3 (angle ?r1 ?r2))
              ((local ?r1) ?f1 ?f3 (dist ?r1 ?r2))
              ((local ?r1) ?f1 ?f2 (dist ?r1 ?r2))
              ((local ?r1) ?f2 ?f3 (speed-diff ?r1 ?r2))
              ((global ?r1 ?r2) ?f1 ?f4 (dist ?r1 ?r2)))
  :body '((?f1 (get-robot-angle-dist ?r1 ?r2))
          (?f2 (calc-robot-speed-diff ?r1 ?r2))
          (?f3 (stalk-robot ?r1 ?r2))
          (?f4 (lead-robot ?r2 ?r1))))

; Top method. If we know which robot who should follow
(make-config-method :name '(do-carry-bar ?r1)
  :precond '((robot ?r1) (robot ?r2) (in ?r1 ?room) (in ?r2 ?room)
             (eval (not (eql (quote ?r1) (quote ?r2)))))
  :channels '(((local ?r1) ?f1 ?f3 (angle ?r1 ?r2))
              ((local ?r1) ?f1 ?f3 (dist ?r1 ?r2))
              ((local ?r1) ?f1 ?f2 (dist ?r1 ?r2))
              ((local ?r1) ?f2 ?f3 (speed-diff ?r1 ?r2))
              ((global ?r1 ?r2) ?f1 ?f4 (dist ?r1 ?r2)))
  :body '((?f1 (get-robot-angle-dist ?r1 ?r2))
          (?f2 (calc-robot-speed-diff ?r1 ?r2))
          (?f3 (stalk-robot ?r1 ?r2))
          (?f4 (lead-robot ?r2 ?r1))))
