;; verdict: error
;; message: lies takes 2 argument(s), 1 given
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
  (:goal (and (lies box))))
