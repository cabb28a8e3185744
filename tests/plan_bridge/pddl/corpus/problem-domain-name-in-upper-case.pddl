;; verdict: valid
;; plan: 3
(define (problem deliver-one)
  (:domain COURIER)
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
  (:goal (and (lies box shop))))
