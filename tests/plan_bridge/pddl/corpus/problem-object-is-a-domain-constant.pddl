;; verdict: error
;; message: object 'depot' is already a constant of the domain
;; pair: depot-constant-domain.pddl
;; where: problem
;; line: 11
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    shop - place
    depot - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
