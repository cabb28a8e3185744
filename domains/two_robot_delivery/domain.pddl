; Two robots fetch items from two storerooms and deliver them, at the same time.
;
; Each robot has one gripper (hand-empty / holding), so it carries one item at a
; time; what a robot can carry is fixed (suits): the manipulator takes the fragile
; kitchen things, the tray robot the parcels. Robots move between connected rooms
; through doors that are passable (a closed or blocked door is not).
;
; Steps of different robots touch different atoms, so the executive can run them
; concurrently (MissionSetup(concurrent=True)); steps of one robot all read or
; write its position or its gripper, so they stay in order.
(define (domain two-robot-delivery)
  (:requirements :strips :typing)
  (:types robot room item)
  (:predicates
    (at ?r - robot ?x - room)
    (connected ?a - room ?b - room)
    (passable ?a - room ?b - room)
    (item-at ?i - item ?x - room)
    (suits ?r - robot ?i - item)
    (holding ?r - robot ?i - item)
    (hand-empty ?r - robot))

  (:action move
    :parameters (?r - robot ?from - room ?to - room)
    :precondition (and (at ?r ?from) (connected ?from ?to) (passable ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  (:action pick
    :parameters (?r - robot ?i - item ?x - room)
    :precondition (and (at ?r ?x) (item-at ?i ?x) (hand-empty ?r) (suits ?r ?i))
    :effect (and (holding ?r ?i) (not (item-at ?i ?x)) (not (hand-empty ?r))))

  (:action drop
    :parameters (?r - robot ?i - item ?x - room)
    :precondition (and (at ?r ?x) (holding ?r ?i))
    :effect (and (item-at ?i ?x) (hand-empty ?r) (not (holding ?r ?i)))))
