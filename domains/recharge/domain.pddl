; Deliver items between rooms, recharging when the battery runs low (SMACH paper,
; PR2 autonomous recharging).
;
; The battery is modelled symbolically: (battery-ok ?r) or (battery-low ?r). The
; planner assumes the battery lasts; a battery monitor running next to every long
; skill preempts it when the charge falls below the reserve, the skill reports
; (battery-low ?r), and the executive replans: go to the charger on reserve power,
; plug in, charge, unplug, resume the deliveries.
(define (domain recharge)
  (:requirements :strips :typing)
  (:types robot room item)
  (:predicates
    (at ?r - robot ?x - room)
    (connected ?a - room ?b - room)
    (item-at ?i - item ?x - room)
    (holding ?r - robot ?i - item)
    (hand-empty ?r - robot)
    (battery-ok ?r - robot)
    (battery-low ?r - robot)
    (charger-at ?x - room)
    (plugged ?r - robot)
    (unplugged ?r - robot))

  (:action move
    :parameters (?r - robot ?from - room ?to - room)
    :precondition (and (at ?r ?from) (connected ?from ?to) (battery-ok ?r) (unplugged ?r))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  ; The docking behaviour drives the whole way to the charger on reserve power.
  (:action go-to-charger
    :parameters (?r - robot ?from - room ?dock - room)
    :precondition (and (at ?r ?from) (battery-low ?r) (charger-at ?dock) (unplugged ?r))
    :effect (and (at ?r ?dock) (not (at ?r ?from))))

  (:action pick
    :parameters (?r - robot ?i - item ?x - room)
    :precondition (and (at ?r ?x) (item-at ?i ?x) (hand-empty ?r) (battery-ok ?r))
    :effect (and (holding ?r ?i) (not (item-at ?i ?x)) (not (hand-empty ?r))))

  (:action place
    :parameters (?r - robot ?i - item ?x - room)
    :precondition (and (at ?r ?x) (holding ?r ?i))
    :effect (and (item-at ?i ?x) (hand-empty ?r) (not (holding ?r ?i))))

  (:action plug-in
    :parameters (?r - robot ?x - room)
    :precondition (and (at ?r ?x) (charger-at ?x) (unplugged ?r))
    :effect (and (plugged ?r) (not (unplugged ?r))))

  (:action charge
    :parameters (?r - robot)
    :precondition (and (plugged ?r) (battery-low ?r))
    :effect (and (battery-ok ?r) (not (battery-low ?r))))

  (:action unplug
    :parameters (?r - robot)
    :precondition (plugged ?r)
    :effect (and (unplugged ?r) (not (plugged ?r)))))
