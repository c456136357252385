;;; Build a wall: Appendix A.3 of R. Lundh, "Plan-Based Configuration of a
;;; Group of Robots" (2006).

;; A.3.1 Sensing resources
(make-functionality :name '(laser ?r) :out '((laser-reading ?r)))
(make-functionality :name '(sonar ?r) :out '((sonar-reading ?r)))

;; A.3.2 Action resources
(make-functionality :name '(push-block ?r ?b ?w)
  :in '((pos ?b ?w) (orient ?b ?w) (orient ?r ?b)))

;; A.3.3 Functionalities
(make-functionality :name '(measure-orient-laser ?r ?o)
  :in '((laser-reading ?r))
  :out '((orient ?r ?o)))
(make-functionality :name '(measure-orient-sonar ?r ?o)
  :in '((sonar-reading ?r))
  :out '((orient ?r ?o)))
(make-functionality :name '(measure-pos-laser ?r ?o)
  :in '((laser-reading ?r))
  :out '((pos ?r ?o)))
; Measures the relative position of block to desired block position
(make-functionality :name '(transform-block-data ?r ?b ?w)
  :in '((pos ?r ?b) (orient ?r ?b) (pos ?r ?w) (orient ?r ?w))
  :out '((pos ?b ?w) (orient ?b ?w)))

;; A.3.4 Methods
; To get information about block
(make-config-method :name '(get-block-data ?r ?b ?w)
  :out '((?f5 (pos ?b ?w)) (?f5 (orient ?b ?w)))
  :channels '(((local ?r) ?f1 ?f5 (pos ?r ?b))
              ((local ?r) ?f2 ?f5 (orient ?r ?b))
              ((local ?r) ?f3 ?f5 (pos ?r ?w))
              ((local ?r) ?f4 ?f5 (orient ?r ?w)))
  :body '((?f1 (get-object-pos ?r ?b))
          (?f2 (get-object-orient ?r ?b))
          (?f3 (get-object-pos ?r ?w))
          (?f4 (get-object-orient ?r ?w))
          (?f5 (transform-block-data ?r ?b ?w))))

; Get orientation of object using laser
(make-config-method :name '(get-object-orient ?r ?o)
  :precond '((laser ?r))
  :out '((?f2 (orient ?r ?o)))
  :channels '(((local ?r) ?f1 ?f2 (laser-reading ?r)))
  :body '((?f1 (laser ?r)) (?f2 (measure-orient-laser ?r ?o))))

; Get orientation of object using sonar
(make-config-method :name '(get-object-orient ?r ?o)
  :precond '((sonar ?r))
  :out '((?f2 (orient ?r ?o)))
  :channels '(((local ?r) ?f1 ?f2 (sonar-reading ?r)))
  :body '((?f1 (sonar ?r)) (?f2 (measure-orient-sonar ?r ?o))))

; Get position of object using laser
(make-config-method :name '(get-object-pos ?r ?o)
  :precond '((laser ?r))
  :out '((?f2 (pos ?r ?o)))
  :channels '(((local ?r) ?f1 ?f2 (laser-reading ?r)))
  :body '((?f1 (laser ?r)) (?f2 (measure-pos-laser ?r ?o))))

; Push left side.
(make-config-method :name '(do-push ?r ?b ?w)
  :precond '((left ?r) (robot ?robserv))
  :channels '(((local ?r) ?f1 ?f3 (orient ?r ?b))
              ((global ?robserv ?r) ?f2 ?f3 (pos ?b ?w))
              ((global ?robserv ?r) ?f2 ?f3 (orient ?b ?w)))
  :body '((?f1 (get-object-orient ?r ?b))
          (?f2 (get-block-data ?robserv ?b ?w))
          (?f3 (push-block ?r ?b ?w))))

; Push right side.
(make-config-method :name '(do-push ?r ?b ?w)
  :precond '((right ?r) (robot ?robserv))
  :channels '(((local ?r) ?f1 ?f3 (orient ?r ?b))
              ((global ?robserv ?r) ?f2 ?f3 (pos ?b ?w))
              ((global ?robserv ?r) ?f2 ?f3 (orient ?b ?w)))
  :body '((?f1 (get-object-orient ?r ?b))
          (?f2 (get-block-data ?robserv ?b ?w))
          (?f3 (push-block ?r ?b ?w))))

;; Top method.
(make-config-method :name '(do-push-block ?rleft ?b ?w)
  :precond '((block ?b) (robot ?rright) (robot ?rleft)
             (eval (not (eql (quote ?rleft) (quote ?rright)))))
  :body '((?f1 (do-push ?rleft ?b ?w))
          (?f2 (do-push ?rright ?b ?w))))
