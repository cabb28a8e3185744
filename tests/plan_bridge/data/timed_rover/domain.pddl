; A rover with a battery inspects sites: driving takes time in proportion to the
; distance and drains the battery; inspecting needs the rover to stay put; it can
; recharge at a station. Written for the user-skill tests (temporal and numeric).
(define (domain timed-rover)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types rover site)
  (:predicates
    (parked ?r - rover ?s - site)
    (route ?a - site ?b - site)
    (inspected ?s - site)
    (station ?s - site))
  (:functions
    (distance ?a - site ?b - site)
    (energy ?r - rover)
    (speed ?r - rover))
  (:durative-action drive
    :parameters (?r - rover ?from - site ?to - site)
    :duration (= ?duration (/ (distance ?from ?to) (speed ?r)))
    :condition (and (at start (parked ?r ?from)) (over all (route ?from ?to))
                    (at start (>= (energy ?r) (distance ?from ?to))))
    :effect (and (at start (not (parked ?r ?from)))
                 (at start (decrease (energy ?r) (distance ?from ?to)))
                 (at end (parked ?r ?to))))
  (:durative-action inspect
    :parameters (?r - rover ?s - site)
    :duration (= ?duration 4)
    :condition (and (over all (parked ?r ?s)) (at start (>= (energy ?r) 2)))
    :effect (and (at start (decrease (energy ?r) 2)) (at end (inspected ?s))))
  (:durative-action recharge
    :parameters (?r - rover ?s - site)
    :duration (= ?duration 6)
    :condition (and (over all (parked ?r ?s)) (at start (station ?s)))
    :effect (at end (assign (energy ?r) 40))))
