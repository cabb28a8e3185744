;; verdict: error
;; message: :constants is a domain section; a problem file cannot have it
;; where: problem
;; line: 7
(define (problem deliver-one)
  (:domain courier)
  (:constants shop - place)
  (:objects
    van - robot
    depot - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
