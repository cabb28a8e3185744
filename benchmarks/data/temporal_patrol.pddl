; Patrol for benchmarks/temporal_bench.py: robots drive chains of waypoints; every
; move counts in one shared numeric fluent, so every pair of moves interferes.
(define (domain temporal-patrol)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types robot waypoint)
  (:predicates (at ?r - robot ?w - waypoint) (link ?a ?b - waypoint)
               (visited ?w - waypoint))
  (:functions (visits))
  (:durative-action move
    :parameters (?r - robot ?a ?b - waypoint)
    :duration (= ?duration 1)
    :condition (and (at start (at ?r ?a)) (over all (link ?a ?b)))
    :effect (and (at start (not (at ?r ?a)))
                 (at end (at ?r ?b))
                 (at end (visited ?b))
                 (at end (increase (visits) 1))))
)
