;; verdict: valid
;; unless-installed: tamer kairos
;; pair: durative-problem.pddl
;; warning: a duration of 0 in (:durative-action drive ...)
;; warning-line: 13
(define (domain courier)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types robot place)
  (:predicates (at ?r - robot ?p - place) (link ?a ?b - place))
  (:functions (distance ?a ?b - place) (travelled ?r - robot))
  (:durative-action drive
    :parameters (?r - robot ?from ?to - place)
    :duration (= ?duration 0)
    :condition (and (at start (at ?r ?from)) (over all (link ?from ?to)))
    :effect (and (at start (not (at ?r ?from))) (at end (at ?r ?to)))))
