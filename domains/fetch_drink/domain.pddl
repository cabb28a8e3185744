; Fetch a drink from the refrigerator and hand it to a person (SMACH paper, PR2).
;
; The robot has one gripper in this model: it needs it free to open the fridge and
; to pick a drink, but closes the fridge with the other arm while holding a drink.
; (clear ?a ?b) is what the robot believes about a corridor; a blocked corridor is
; observed false by the navigation skill, and the planner routes around it.
(define (domain fetch-drink)
  (:requirements :strips :typing)
  (:types robot place fridge shelf drink person)
  (:predicates
    (at ?r - robot ?p - place)
    (connected ?a - place ?b - place)
    (clear ?a - place ?b - place)
    (fridge-in ?f - fridge ?p - place)
    (fridge-open ?f - fridge)
    (fridge-closed ?f - fridge)
    (shelf-of ?s - shelf ?f - fridge)
    (on ?d - drink ?s - shelf)
    (hand-empty ?r - robot)
    (holding ?r - robot ?d - drink)
    (person-at ?h - person ?p - place)
    (served ?h - person ?d - drink))

  (:action navigate
    :parameters (?r - robot ?from - place ?to - place)
    :precondition (and (at ?r ?from) (connected ?from ?to) (clear ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  (:action open-fridge
    :parameters (?r - robot ?f - fridge ?p - place)
    :precondition (and (at ?r ?p) (fridge-in ?f ?p) (fridge-closed ?f) (hand-empty ?r))
    :effect (and (fridge-open ?f) (not (fridge-closed ?f))))

  (:action pick-drink
    :parameters (?r - robot ?d - drink ?s - shelf ?f - fridge ?p - place)
    :precondition (and (at ?r ?p) (fridge-in ?f ?p) (fridge-open ?f) (shelf-of ?s ?f)
                       (on ?d ?s) (hand-empty ?r))
    :effect (and (holding ?r ?d) (not (on ?d ?s)) (not (hand-empty ?r))))

  (:action close-fridge
    :parameters (?r - robot ?f - fridge ?p - place)
    :precondition (and (at ?r ?p) (fridge-in ?f ?p) (fridge-open ?f))
    :effect (and (fridge-closed ?f) (not (fridge-open ?f))))

  (:action hand-over
    :parameters (?r - robot ?d - drink ?h - person ?p - place)
    :precondition (and (at ?r ?p) (holding ?r ?d) (person-at ?h ?p))
    :effect (and (served ?h ?d) (hand-empty ?r) (not (holding ?r ?d)))))
