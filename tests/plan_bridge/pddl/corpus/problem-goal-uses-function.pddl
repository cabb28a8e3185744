;; verdict: error
;; message: undeclared function 'fuel'
;; where: problem
;; line: 17
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
  (:goal (and (lies box shop) (> (fuel van) 3))))
