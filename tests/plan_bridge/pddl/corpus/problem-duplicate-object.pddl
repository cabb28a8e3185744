;; verdict: error
;; message: 'depot' appears twice in the objects
;; where: problem
;; line: 9
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop depot - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
