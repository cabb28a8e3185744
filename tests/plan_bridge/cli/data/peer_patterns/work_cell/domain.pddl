; A mobile manipulator in a work cell, written the way RoboCup@Work stacks write it:
; classical actions with action costs, `object` among the declared types, negative
; preconditions, and upper-case names with dashes coming from a knowledge base.
(define (domain work-cell)
  (:requirements :typing :negative-preconditions :action-costs)
  (:types location robot object platform)
  (:predicates (robot-at ?r - robot ?l - location)
               (object-on ?o - object ?l - location)
               (holding ?r - robot ?o - object)
               (gripper-free ?r - robot)
               (stowed ?o - object ?p - platform)
               (platform-full ?p - platform)
               (seen ?l - location))
  (:functions (total-cost) - number)
  (:action move_base
    :parameters (?r - robot ?from ?to - location)
    :precondition (and (robot-at ?r ?from) (gripper-free ?r))
    :effect (and (not (robot-at ?r ?from)) (robot-at ?r ?to) (not (seen ?from))
                 (increase (total-cost) 10)))
  (:action perceive
    :parameters (?r - robot ?l - location)
    :precondition (and (robot-at ?r ?l) (not (seen ?l)))
    :effect (and (seen ?l) (increase (total-cost) 3)))
  (:action pick
    :parameters (?r - robot ?l - location ?o - object)
    :precondition (and (robot-at ?r ?l) (seen ?l) (object-on ?o ?l) (gripper-free ?r))
    :effect (and (holding ?r ?o) (not (object-on ?o ?l)) (not (gripper-free ?r))
                 (increase (total-cost) 2)))
  (:action place
    :parameters (?r - robot ?l - location ?o - object)
    :precondition (and (robot-at ?r ?l) (holding ?r ?o))
    :effect (and (object-on ?o ?l) (not (holding ?r ?o)) (gripper-free ?r)
                 (increase (total-cost) 2)))
  (:action stow
    :parameters (?r - robot ?p - platform ?o - object)
    :precondition (and (holding ?r ?o) (not (platform-full ?p)))
    :effect (and (stowed ?o ?p) (platform-full ?p) (not (holding ?r ?o)) (gripper-free ?r)
                 (increase (total-cost) 1)))
  (:action unstow
    :parameters (?r - robot ?p - platform ?o - object)
    :precondition (and (stowed ?o ?p) (gripper-free ?r))
    :effect (and (holding ?r ?o) (not (stowed ?o ?p)) (not (platform-full ?p))
                 (not (gripper-free ?r)) (increase (total-cost) 1))))
