; Clearing a table onto a cart, then pushing the cart to the kitchen.
; After the PR2 "clearing a table while pushing a cart" demo of the SMACH paper.
;
; The robot has one arm (hand-empty / holding). Objects lie on spots: table zones
; or the floor next to the table. From a location the arm reaches some spots
; (reaches). The robot walks between adjacent locations of the dining room; the
; corridors to the kitchen it takes only with the cart, through passages wide
; enough for the cart that are not blocked (clear).
(define (domain table-clearing)
  (:requirements :strips :typing)
  (:types robot cart location spot item)
  (:predicates
    (robot-at ?r - robot ?l - location)
    (cart-at ?c - cart ?l - location)
    (adjacent ?a - location ?b - location)
    (passage ?a - location ?b - location)
    (clear ?a - location ?b - location)
    (reaches ?l - location ?p - spot)
    (item-at ?i - item ?p - spot)
    (on-cart ?i - item ?c - cart)
    (holding ?r - robot ?i - item)
    (hand-empty ?r - robot))

  (:action move
    :parameters (?r - robot ?from - location ?to - location)
    :precondition (and (robot-at ?r ?from) (adjacent ?from ?to))
    :effect (and (robot-at ?r ?to) (not (robot-at ?r ?from))))

  (:action pick
    :parameters (?r - robot ?i - item ?p - spot ?l - location)
    :precondition (and (robot-at ?r ?l) (reaches ?l ?p) (item-at ?i ?p) (hand-empty ?r))
    :effect (and (holding ?r ?i) (not (item-at ?i ?p)) (not (hand-empty ?r))))

  (:action place
    :parameters (?r - robot ?i - item ?c - cart ?l - location)
    :precondition (and (robot-at ?r ?l) (cart-at ?c ?l) (holding ?r ?i))
    :effect (and (on-cart ?i ?c) (hand-empty ?r) (not (holding ?r ?i))))

  ; Both hands are on the cart's handle: the robot must not hold anything.
  (:action push-cart
    :parameters (?r - robot ?c - cart ?from - location ?to - location)
    :precondition (and (robot-at ?r ?from) (cart-at ?c ?from) (hand-empty ?r)
                       (passage ?from ?to) (clear ?from ?to))
    :effect (and (robot-at ?r ?to) (cart-at ?c ?to)
                 (not (robot-at ?r ?from)) (not (cart-at ?c ?from)))))
