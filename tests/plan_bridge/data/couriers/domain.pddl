; Couriers carry parcels between rooms of a corridor: one parcel at a time.
(define (domain couriers)
  (:requirements :strips :typing)
  (:types courier room parcel)
  (:predicates
    (in ?c - courier ?r - room)
    (door ?a ?b - room)
    (lies ?p - parcel ?r - room)
    (carries ?c - courier ?p - parcel)
    (free ?c - courier))
  (:action walk
    :parameters (?c - courier ?from ?to - room)
    :precondition (and (in ?c ?from) (door ?from ?to))
    :effect (and (in ?c ?to) (not (in ?c ?from))))
  (:action take
    :parameters (?c - courier ?p - parcel ?r - room)
    :precondition (and (in ?c ?r) (lies ?p ?r) (free ?c))
    :effect (and (carries ?c ?p) (not (lies ?p ?r)) (not (free ?c))))
  (:action leave
    :parameters (?c - courier ?p - parcel ?r - room)
    :precondition (and (in ?c ?r) (carries ?c ?p))
    :effect (and (lies ?p ?r) (free ?c) (not (carries ?c ?p)))))
