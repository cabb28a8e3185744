(define (domain courier)
  (:requirements :strips :typing :numeric-fluents)
  (:types robot place)
  (:predicates (at ?r - robot ?p - place) (link ?from ?to - place))
  (:functions (battery ?r - robot))
  (:action move
    :parameters (?r - robot ?from ?to - place)
    :precondition (and (at ?r ?from) (link ?from ?to) (>= (battery ?r) 1))
    :effect (and (at ?r ?to) (not (at ?r ?from)) (decrease (battery ?r) 1))))
