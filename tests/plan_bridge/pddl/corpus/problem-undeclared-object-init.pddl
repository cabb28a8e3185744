;; verdict: error
;; message: undeclared object or constant 'store'
;; where: problem
;; line: 15
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
    (link depot store)
    (link shop depot))
  (:goal (and (lies box shop))))
