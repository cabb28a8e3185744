;; verdict: error
;; message: nested-forall-effect (a forall effect inside another forall effect) is not supported
;; where: domain
;; line: 27
(define (domain courier)
  (:requirements :strips :typing :negative-preconditions :conditional-effects)
  (:types robot place parcel - object)
  (:predicates
    (at ?r - robot ?p - place)
    (lies ?c - parcel ?p - place)
    (carries ?r - robot ?c - parcel)
    (link ?from - place ?to - place)
    (empty ?r - robot))
  (:action drive
    :parameters (?r - robot ?from - place ?to - place)
    :precondition (and (at ?r ?from) (link ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))
  (:action load
    :parameters (?r - robot ?c - parcel ?p - place)
    :precondition (and (at ?r ?p) (lies ?c ?p) (empty ?r))
    :effect (and (carries ?r ?c) (not (lies ?c ?p)) (not (empty ?r))))
  (:action drop-everything
    :parameters (?r - robot ?p - place)
    :precondition (at ?r ?p)
    :effect (forall (?c - parcel)
              (and (not (carries ?r ?c))
                   (forall (?q - place) (when (link ?p ?q) (lies ?c ?p))))))
  (:action unload
    :parameters (?r - robot ?c - parcel ?p - place)
    :precondition (and (at ?r ?p) (carries ?r ?c) (not (empty ?r)))
    :effect (and (lies ?c ?p) (empty ?r) (not (carries ?r ?c)))))
