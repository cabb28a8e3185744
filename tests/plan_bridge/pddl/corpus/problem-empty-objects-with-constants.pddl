;; verdict: valid
;; plan: 3
;; pair: all-constants-domain.pddl
(define (problem deliver-one)
  (:domain courier)
  (:objects)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
