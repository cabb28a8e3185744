(define (domain courier)
  (:requirements :strips :typing :durative-actions)
  (:types robot place)
  (:predicates (at ?r - robot ?p - place) (link ?a ?b - place))
  (:durative-action drive
    :parameters (?r - robot ?from ?to - place)
    :duration (= ?duration 3)
    :condition (and (at start (at ?r ?from)) (over all (link ?from ?to)))
    :effect (and (at start (not (at ?r ?from))) (at end (at ?r ?to)))))
