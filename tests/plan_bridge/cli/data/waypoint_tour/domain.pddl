; A robot tours waypoints. Its problems leave the goal to the knowledge base (kb.pddl)
; or give one (tour.pddl): `plan-bridge run ... --goal "(visited wp3)"` plans another.
(define (domain waypoint-tour)
  (:requirements :strips :typing)
  (:types robot waypoint)
  (:constants dock - waypoint)
  (:predicates (at ?r - robot ?w - waypoint)
               (linked ?from ?to - waypoint)
               (visited ?w - waypoint)
               (charging ?r - robot))
  (:action drive
    :parameters (?r - robot ?from ?to - waypoint)
    :precondition (and (at ?r ?from) (linked ?from ?to))
    :effect (and (not (at ?r ?from)) (at ?r ?to) (visited ?to) (not (charging ?r))))
  (:action plug-in
    :parameters (?r - robot)
    :precondition (at ?r dock)
    :effect (charging ?r)))
