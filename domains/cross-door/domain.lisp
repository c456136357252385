;;; Cross a door: Appendix A.1 of R. Lundh, "Plan-Based Configuration of a
;;; Group of Robots" (2006). The PDF interleaves the lines of do-cross-door;
;;; its text here is de-interleaved to agree with section 4.6.

;; A.1.1 Sensing resources
(make-functionality :name '(camera ?r) :out '((image ?r)))
(make-functionality :name '(compass ?r) :out '((global-orient ?r)))

;; A.1.2 Action resources
(make-functionality :name '(cross-door ?r ?d) :in '((pos ?r ?d) (orient ?r ?d)))

;; A.1.3 Functionalities
;; For all functions with ?r and ?rh1:
;;   ?r represents the robot crossing the gate
;;   ?rh1 represents the robot helping
(make-functionality :name '(measure-door ?r ?d)
  :in '((image ?r))
  :out '((pos ?r ?d) (orient ?r ?d)))
(make-functionality :name '(measure-robot-pos ?rh1 ?r)
  :in '((image ?rh1))
  :out '((pos ?rh1 ?r)))
(make-functionality :name '(measure-robot-angle ?r ?o)
  :in '((image ?r))
  :out '((angle ?r ?o)))
(make-functionality :name '(measure-robot-orient-compass ?rh1 ?r)
  :precond '((compass ?rh1) (compass ?r))
  :in '((global-orient ?rh1) (global-orient ?r))
  :out '((orient ?rh1 ?r)))
(make-functionality :name '(measure-robot-orient-camera ?rh1 ?r)
  :in '((angle ?rh1 ?r) (angle ?r ?rh1))
  :out '((orient ?rh1 ?r)))
; transforms pos and orient of door in ?rh1 coords to
; pos and orient in ?r coords. Conf 3 and 4
(make-functionality :name '(transform-info ?rh1 ?r ?d)
  :in '((orient ?rh1 ?r) (pos ?rh1 ?r) (orient ?rh1 ?d) (pos ?rh1 ?d))
  :out '((orient ?r ?d) (pos ?r ?d)))

;; A.1.4 Methods
; Use camera to measure-door.
(make-config-method :name '(get-door-info ?r ?d)
  :precond '((camera ?r) (in ?r ?room) (in ?d ?room) (robot ?r) (door ?d))
  :out '((?f2 (pos ?r ?d)) (?f2 (orient ?r ?d)))
  :channels '(((local ?r) ?f1 ?f2 (image ?r)))
  :body '((?f1 (camera ?r)) (?f2 (measure-door ?r ?d))))

; Use compasses to get robot orient in rh1 coords.
(make-config-method :name '(get-robot-orient ?rh1 ?r)
  :precond '((compass ?rh1) (compass ?r))
  :out '((?f3 (orient ?rh1 ?r)))
  :channels '(((global ?r ?rh1) ?f1 ?f3 (global-orient ?r))
              ((local ?rh1) ?f2 ?f3 (global-orient ?rh1)))
  :body '((?f1 (compass ?r))
          (?f2 (compass ?rh1))
          (?f3 (measure-robot-orient-compass ?rh1 ?r))))

; Use camera to get robot pos in rh1 coords.
(make-config-method :name '(get-robot-pos ?rh1 ?r)
  :precond '((camera ?rh1))
  :out '((?f2 (pos ?rh1 ?r)))
  :channels '(((local ?rh1) ?f1 ?f2 (image ?rh1)))
  :body '((?f1 (camera ?rh1)) (?f2 (measure-robot-pos ?rh1 ?r))))

; Uses camera to measure the angle to another robot.
(make-config-method :name '(get-robot-angle ?r ?o)
  :precond '((camera ?r))
  :out '((?f2 (angle ?r ?o)))
  :channels '(((local ?r) ?f1 ?f2 (image ?r)))
  :body '((?f1 (camera ?r)) (?f2 (measure-robot-angle ?r ?o))))

; Combines the angular informations of two robots to get the orient.
(make-config-method :name '(get-robot-orient ?rh1 ?r)
  :precond '((camera ?r) (camera ?rh1))
  :out '((?f3 (orient ?rh1 ?r)))
  :channels '(((local ?rh1) ?f1 ?f3 (angle ?rh1 ?r))
              ((global ?r ?rh1) ?f2 ?f3 (angle ?r ?rh1)))
  :body '((?f1 (get-robot-angle ?rh1 ?r))
          (?f2 (get-robot-angle ?r ?rh1))
          (?f3 (measure-robot-orient-camera ?rh1 ?r))))

; Use info about door and robot in rh1 coords to get info about door in
; r coords. Robot pos and orient from different methods.
(make-config-method :name '(get-door-info ?rh1 ?r ?d)
  :out '((?f4 (pos ?r ?d)) (?f4 (orient ?r ?d)))
  :channels '(((local ?rh1) ?f1 ?f4 (pos ?rh1 ?d))
              ((local ?rh1) ?f1 ?f4 (orient ?rh1 ?d))
              ((local ?rh1) ?f2 ?f4 (orient ?rh1 ?r))
              ((local ?rh1) ?f3 ?f4 (pos ?rh1 ?r)))
  :body '((?f1 (get-door-info ?rh1 ?d))
          (?f2 (get-robot-orient ?rh1 ?r))
          (?f3 (get-robot-pos ?rh1 ?r))
          (?f4 (transform-info ?rh1 ?r ?d))))

; Top method. ?r is the robot that should cross door ?d,
; using door information from the helping robot ?rh1.
(make-config-method :name '(do-cross-door ?r ?d)
  :precond '((robot ?r) (door ?d) (robot ?rh1) (open ?d)
             (eval (not (eql (quote ?r) (quote ?rh1)))))
  :channels '(((global ?rh1 ?r) ?f1 ?f2 (pos ?r ?d))
              ((global ?rh1 ?r) ?f1 ?f2 (orient ?r ?d)))
  :body '((?f1 (get-door-info ?rh1 ?r ?d))
          (?f2 (cross-door ?r ?d))))
