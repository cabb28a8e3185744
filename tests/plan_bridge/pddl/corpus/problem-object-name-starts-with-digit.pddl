;; verdict: error
;; message: '2nd-box' in the objects: a PDDL name starts with a letter
;; where: problem
;; line: 10
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box 2nd-box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
