;; verdict: valid
;; plan: 3
(define (problem deliver-one)
  (:goal (and (lies box shop)))
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:domain courier))
