;;; Keeping watch over a door (a test domain of the takeover, not from the
;;; thesis): one robot's camera sees the door, and another keeps the log. The
;;; goal names the three robots that may take part, so its order of succession
;;; has three (5.5): the logger first, then the watcher, then a second logger.

(make-functionality :name '(camera ?r) :out '((image ?r)))
(make-functionality :name '(detect ?r ?d) :in '((image ?r)) :out '((door-state ?d)))
(make-functionality :name '(keep-log ?r ?d) :in '((door-state ?d)))

; ?a keeps the log of what ?b's camera sees of ?d.
(make-config-method :name '(do-watch ?a ?b ?c ?d)
  :precond '((robot ?a) (robot ?b) (camera ?b) (door ?d))
  :channels '(((local ?b) ?f1 ?f2 (image ?b))
              ((global ?b ?a) ?f2 ?f3 (door-state ?d)))
  :body '((?f1 (camera ?b)) (?f2 (detect ?b ?d)) (?f3 (keep-log ?a ?d))))

; Without ?a: ?c keeps it.
(make-config-method :name '(do-watch ?a ?b ?c ?d)
  :precond '((robot ?c) (robot ?b) (camera ?b) (door ?d))
  :channels '(((local ?b) ?f1 ?f2 (image ?b))
              ((global ?b ?c) ?f2 ?f3 (door-state ?d)))
  :body '((?f1 (camera ?b)) (?f2 (detect ?b ?d)) (?f3 (keep-log ?c ?d))))
