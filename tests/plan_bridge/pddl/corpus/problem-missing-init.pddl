;; verdict: valid
;; plan: 0
;; warning: the goal is empty
;; warning-line: 11
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:goal (and)))
