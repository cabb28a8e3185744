; Reach a goal room through doors (SMACH paper, PR2 door opening).
;
; The robot believes every door is unlocked; a locked door is discovered only when
; the open-door skill tries its handle, which then reports (unlocked ?d) false and
; the planner routes around it. Rooms may also be joined by open passages.
; door-between is listed in both directions.
(define (domain door-opening)
  (:requirements :strips :typing)
  (:types robot room door)
  (:predicates
    (at ?r - robot ?x - room)
    (passage ?a - room ?b - room)
    (door-between ?d - door ?a - room ?b - room)
    (door-open ?d - door)
    (door-closed ?d - door)
    (unlocked ?d - door))

  (:action move
    :parameters (?r - robot ?from - room ?to - room)
    :precondition (and (at ?r ?from) (passage ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  (:action open-door
    :parameters (?r - robot ?d - door ?from - room ?to - room)
    :precondition (and (at ?r ?from) (door-between ?d ?from ?to) (door-closed ?d) (unlocked ?d))
    :effect (and (door-open ?d) (not (door-closed ?d))))

  (:action pass-door
    :parameters (?r - robot ?d - door ?from - room ?to - room)
    :precondition (and (at ?r ?from) (door-between ?d ?from ?to) (door-open ?d))
    :effect (and (at ?r ?to) (not (at ?r ?from)))))
