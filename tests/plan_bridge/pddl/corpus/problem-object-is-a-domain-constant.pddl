;; verdict: valid
;; pair: depot-constant-domain.pddl
;; warning: object 'depot' (line 11) is already a constant of the domain
;; warning-line: 11
;; plan: 3
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
