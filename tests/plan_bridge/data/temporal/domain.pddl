; Night patrol: a bot undocks and inspects a spot, which needs its light on the
; whole time; a second bot must keep the light switched on meanwhile (overlap).
(define (domain night-patrol)
  (:requirements :strips :typing :negative-preconditions :durative-actions :numeric-fluents)
  (:types bot spot)
  (:predicates (docked ?b - bot) (at ?b - bot ?s - spot) (light-on ?s - spot)
               (inspected ?s - spot))
  (:functions (energy ?b - bot) (rounds))
  (:durative-action undock
    :parameters (?b - bot ?s - spot)
    :duration (= ?duration 1)
    :condition (and (at start (docked ?b)) (over all (at ?b ?s)))
    :effect (at end (not (docked ?b))))
  (:durative-action hold-light
    :parameters (?b - bot ?s - spot)
    :duration (= ?duration 4)
    :condition (over all (at ?b ?s))
    :effect (and (at start (light-on ?s)) (at end (not (light-on ?s)))))
  (:durative-action inspect
    :parameters (?b - bot ?s - spot)
    :duration (= ?duration 2)
    :condition (and (at start (not (docked ?b))) (at start (>= (energy ?b) 5))
                    (over all (light-on ?s)) (over all (at ?b ?s)))
    :effect (and (at end (inspected ?s)) (at end (decrease (energy ?b) 5))
                 (at end (increase (rounds) 1))))
)
