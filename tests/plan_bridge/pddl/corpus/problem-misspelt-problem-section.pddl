;; verdict: error
;; message: unknown problem section ':goals'
;; where: problem
;; line: 17
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
  (:goals (and (lies box shop))))
