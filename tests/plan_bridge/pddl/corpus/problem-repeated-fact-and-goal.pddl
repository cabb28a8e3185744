;; verdict: valid
;; plan: 3
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
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop) (lies box shop))))
