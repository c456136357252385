(LET ((CH-1 (make-global-channel 'Emil 'F7 'F5 '(dist Emil Pippi))))
  (LAMBDA NIL
    (PROGN (lead-robot 'Emil CH-1))))
