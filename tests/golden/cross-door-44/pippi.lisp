(LET ((CH-1 (make-global-channel 'Emil 'F10 'F12 '(global-orient Pippi)))
      (CH-2 (make-global-channel 'Emil 'F7 'F3 '(pos Pippi Door1)))
      (CH-3 (make-global-channel 'Emil 'F7 'F3 '(orient Pippi Door1))))
  (LAMBDA NIL
    (PROGN (compass (LIST CH-1))
           (cross-door 'Door1 CH-2 CH-3))))
