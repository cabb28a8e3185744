; Required concurrency, as in the match-cellar examples robot planners ship: the
; photograph needs the lamp lit throughout, and the lamp goes out at its own end,
; so the two actions must overlap.
(define (domain lamp-photo)
  (:requirements :typing :durative-actions :negative-preconditions)
  (:types lamp scene)
  (:predicates (lit ?l - lamp) (fresh ?l - lamp) (camera-free) (photographed ?s - scene))
  (:durative-action switch-on
    :parameters (?l - lamp)
    :duration (= ?duration 6)
    :condition (at start (fresh ?l))
    :effect (and (at start (not (fresh ?l))) (at start (lit ?l)) (at end (not (lit ?l)))))
  (:durative-action photograph
    :parameters (?s - scene ?l - lamp)
    :duration (= ?duration 4)
    :condition (and (at start (camera-free)) (over all (lit ?l)))
    :effect (and (at start (not (camera-free))) (at end (camera-free))
                 (at end (photographed ?s)))))
