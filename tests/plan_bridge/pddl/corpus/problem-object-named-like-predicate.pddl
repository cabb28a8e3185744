;; verdict: error
;; message: has the name of a predicate
;; where: problem
;; line: 10
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    link - parcel)
  (:init
    (at van depot)
    (lies link depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies link shop))))
