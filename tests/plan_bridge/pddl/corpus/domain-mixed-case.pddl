;; verdict: valid
;; plan: 3
(define (domain courier)
  (:requirements :strips :typing :negative-preconditions)
  (:TYPES Robot place parcel - object)
  (:predicates
    (AT ?r - Robot ?p - place)
    (lies ?c - parcel ?p - place)
    (carries ?r - Robot ?c - parcel)
    (link ?from - place ?to - place)
    (empty ?r - Robot))
  (:ACTION Drive
    :parameters (?r - Robot ?from - place ?to - place)
    :precondition (and (AT ?r ?from) (link ?from ?to))
    :effect (and (AT ?r ?to) (not (AT ?r ?from))))
  (:ACTION load
    :parameters (?r - Robot ?c - parcel ?p - place)
    :precondition (and (AT ?r ?p) (lies ?c ?p) (empty ?r))
    :effect (and (carries ?r ?c) (not (lies ?c ?p)) (not (empty ?r))))
  (:ACTION unload
    :parameters (?r - Robot ?c - parcel ?p - place)
    :precondition (and (AT ?r ?p) (carries ?r ?c) (not (empty ?r)))
    :effect (and (lies ?c ?p) (empty ?r) (not (carries ?r ?c)))))
