;; verdict: error
;; message: :vars (PDDL 1.2 free variables of an action) is not supported
;; where: domain
;; line: 16
(define (domain courier)
  (:requirements :strips :typing :negative-preconditions)
  (:types robot place parcel - object)
  (:predicates
    (at ?r - robot ?p - place)
    (lies ?c - parcel ?p - place)
    (carries ?r - robot ?c - parcel)
    (link ?from - place ?to - place)
    (empty ?r - robot))
  (:action drive
    :parameters (?r - robot ?to - place)
    :vars (?from - place)
    :precondition (and (at ?r ?from) (link ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))
  (:action load
    :parameters (?r - robot ?c - parcel ?p - place)
    :precondition (and (at ?r ?p) (lies ?c ?p) (empty ?r))
    :effect (and (carries ?r ?c) (not (lies ?c ?p)) (not (empty ?r))))
  (:action unload
    :parameters (?r - robot ?c - parcel ?p - place)
    :precondition (and (at ?r ?p) (carries ?r ?c) (not (empty ?r)))
    :effect (and (lies ?c ?p) (empty ?r) (not (carries ?r ?c)))))
