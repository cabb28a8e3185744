;; verdict: valid
;; plan: 0
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:goal (and)))
