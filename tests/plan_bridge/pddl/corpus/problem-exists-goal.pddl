;; verdict: valid
;; plan: 3
;; warning: uses :existential-preconditions
;; warning-line: 17
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
    (link depot shop)
    (link shop depot))
  (:goal (exists (?p - place) (and (lies box ?p) (link depot ?p)))))
