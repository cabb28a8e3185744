;; verdict: error
;; message: undeclared function 'total-cost' in (:metric ...)
;; where: problem
;; line: 18
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop)))
  (:metric minimize (total-cost)))
