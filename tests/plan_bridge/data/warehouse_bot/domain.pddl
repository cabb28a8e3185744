; A mobile manipulator in a small warehouse: it drives between zones joined by
; aisles, scans a zone to find what is there, picks a crate and stows it on a rack.
; Written for the user-skill tests (one action is a user's own skill).
(define (domain warehouse-bot)
  (:requirements :strips :typing)
  (:types agent zone crate)
  (:predicates
    (located ?b - agent ?z - zone)
    (aisle ?from - zone ?to - zone)
    (crate-in ?c - crate ?z - zone)
    (scanned ?z - zone)
    (gripper-empty ?b - agent)
    (carrying ?b - agent ?c - crate)
    (rack ?z - zone)
    (stowed ?c - crate))
  (:action drive
    :parameters (?b - agent ?from - zone ?to - zone)
    :precondition (and (located ?b ?from) (aisle ?from ?to))
    :effect (and (not (located ?b ?from)) (located ?b ?to)))
  (:action scan
    :parameters (?b - agent ?z - zone)
    :precondition (located ?b ?z)
    :effect (scanned ?z))
  (:action pick
    :parameters (?b - agent ?c - crate ?z - zone)
    :precondition (and (located ?b ?z) (scanned ?z) (crate-in ?c ?z) (gripper-empty ?b))
    :effect (and (not (crate-in ?c ?z)) (not (gripper-empty ?b)) (carrying ?b ?c)))
  (:action stow
    :parameters (?b - agent ?c - crate ?z - zone)
    :precondition (and (located ?b ?z) (carrying ?b ?c) (rack ?z))
    :effect (and (not (carrying ?b ?c)) (gripper-empty ?b) (stowed ?c) (crate-in ?c ?z))))
