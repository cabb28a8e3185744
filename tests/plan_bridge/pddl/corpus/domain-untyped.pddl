;; verdict: valid
;; plan: 3
;; pair: untyped-problem.pddl
(define (domain courier)
  (:requirements :strips)
  (:predicates (robot ?r) (place ?p) (parcel ?c) (at ?r ?p) (lies ?c ?p) (carries ?r ?c) (link ?a ?b) (empty ?r))
  (:action drive :parameters (?r ?from ?to)
    :precondition (and (robot ?r) (at ?r ?from) (link ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))
  (:action load :parameters (?r ?c ?p)
    :precondition (and (robot ?r) (parcel ?c) (at ?r ?p) (lies ?c ?p) (empty ?r))
    :effect (and (carries ?r ?c) (not (lies ?c ?p)) (not (empty ?r))))
  (:action unload :parameters (?r ?c ?p)
    :precondition (and (at ?r ?p) (carries ?r ?c))
    :effect (and (lies ?c ?p) (empty ?r) (not (carries ?r ?c)))))
