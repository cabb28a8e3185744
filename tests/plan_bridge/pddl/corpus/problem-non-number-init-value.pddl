;; verdict: error
;; message: expected a number
;; pair: fuel-domain.pddl
;; where: problem
;; line: 16
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
    (= (fuel van) full)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
