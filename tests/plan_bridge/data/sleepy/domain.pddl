; A robot moves between rooms through doors and carries one item at a time.
(define (domain rooms)
  (:requirements :strips :typing :conditional-effects :universal-preconditions :existential-preconditions)
  (:types robot room item)
  (:predicates (at ?r - robot ?x - room) (connected ?a - room ?b - room) (open ?a - room ?b - room)
               (item-at ?i - item ?x - room) (holding ?r - robot ?i - item) (free ?r - robot)
               (lights-on ?x - room))
  (:action move
    :parameters (?r - robot ?from - room ?to - room)
    :precondition (and (at ?r ?from) (connected ?from ?to) (open ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))
                 (forall (?i - item) (when (holding ?r ?i) (not (item-at ?i ?from))))))
  (:action pick
    :parameters (?r - robot ?i - item ?x - room)
    :precondition (and (at ?r ?x) (item-at ?i ?x) (free ?r))
    :effect (and (holding ?r ?i) (not (item-at ?i ?x)) (not (free ?r))))
  (:action drop
    :parameters (?r - robot ?i - item ?x - room)
    :precondition (and (at ?r ?x) (holding ?r ?i))
    :effect (and (item-at ?i ?x) (not (holding ?r ?i)) (free ?r)))
  (:action switch-on
    :parameters (?r - robot ?x - room)
    :precondition (and (at ?r ?x) (exists (?i - item) (item-at ?i ?x)))
    :effect (lights-on ?x)))
