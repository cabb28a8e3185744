;; verdict: valid
;; plan: 3
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot-1 shop_2 - place
    box - parcel)
  (:init
    (at van depot-1)
    (lies box depot-1)
    (empty van)
    (link depot-1 shop_2)
    (link shop_2 depot-1))
  (:goal (and (lies box shop_2))))
