;; verdict: error
;; message: undeclared predicate 'idle'
;; where: problem
;; line: 14
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (idle van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
