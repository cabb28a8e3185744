;; verdict: error
;; message: a duration of -2 in (:durative-action drive ...): a durative action cannot take negative time
;; pair: durative-problem.pddl
;; where: domain
;; line: 13
(define (domain courier)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types robot place)
  (:predicates (at ?r - robot ?p - place) (link ?a ?b - place))
  (:functions (distance ?a ?b - place) (travelled ?r - robot))
  (:durative-action drive
    :parameters (?r - robot ?from ?to - place)
    :duration (= ?duration -2)
    :condition (and (at start (at ?r ?from)) (over all (link ?from ?to)))
    :effect (and (at start (not (at ?r ?from))) (at end (at ?r ?to)))))
