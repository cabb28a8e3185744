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
    (robot van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
