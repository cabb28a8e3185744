; A patrol robot with a battery, written the way PlanSys2 and ROSPlan robot domains
; are: durative actions, a numeric battery drained by driving and refilled at a
; charger (a constant of the domain), durations computed from numbers, and `-type`
; written without its space.
(define (domain battery-patrol)
  (:requirements :typing :durative-actions :numeric-fluents)
  (:types robot waypoint -object)
  (:constants charger -waypoint)
  (:predicates (robot_at ?r -robot ?w -waypoint)
               (path ?from ?to - waypoint)
               (inspected ?w - waypoint))
  (:functions (battery ?r - robot)
              (speed ?r - robot)
              (path_length ?from ?to - waypoint))
  (:durative-action drive
    :parameters (?r - robot ?from ?to - waypoint)
    :duration (= ?duration (/ (path_length ?from ?to) (speed ?r)))
    :condition (and (at start (robot_at ?r ?from))
                    (at start (path ?from ?to))
                    (at start (>= (battery ?r) (* 2 (path_length ?from ?to)))))
    :effect (and (at start (not (robot_at ?r ?from)))
                 (at start (decrease (battery ?r) (* 2 (path_length ?from ?to))))
                 (at end (robot_at ?r ?to))))
  (:durative-action inspect
    :parameters (?r - robot ?w - waypoint)
    :duration (= ?duration 3)
    :condition (over all (robot_at ?r ?w))
    :effect (at end (inspected ?w)))
  (:durative-action recharge
    :parameters (?r - robot)
    :duration (= ?duration 5)
    :condition (over all (robot_at ?r charger))
    :effect (at end (assign (battery ?r) 100))))
