; A courier robot drives between rooms and picks up parcels.
(define (domain courier)
  (:requirements :strips :typing)
  (:types robot room parcel)
  (:predicates (robot-at ?r - robot ?x - room)
               (door ?a - room ?b - room)
               (parcel-at ?p - parcel ?x - room)
               (carrying ?r - robot ?p - parcel)
               (gripper-free ?r - robot))
  (:action drive
    :parameters (?r - robot ?from - room ?to - room)
    :precondition (and (robot-at ?r ?from) (door ?from ?to))
    :effect (and (robot-at ?r ?to) (not (robot-at ?r ?from))))
  (:action grab
    :parameters (?r - robot ?p - parcel ?x - room)
    :precondition (and (robot-at ?r ?x) (parcel-at ?p ?x) (gripper-free ?r))
    :effect (and (carrying ?r ?p) (not (parcel-at ?p ?x)) (not (gripper-free ?r))))
  (:action release
    :parameters (?r - robot ?p - parcel ?x - room)
    :precondition (and (robot-at ?r ?x) (carrying ?r ?p))
    :effect (and (parcel-at ?p ?x) (not (carrying ?r ?p)) (gripper-free ?r))))
