;; verdict: valid
;; plan: 3
;; warning: type 'parcel' has the name of an object
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    parcel - parcel)
  (:init
    (at van depot)
    (lies parcel depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies parcel shop))))
